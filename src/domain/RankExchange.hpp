// Messages between the MPI ranks of one run: the collectives and byte messages the engine's exchanges need.
#pragma once
#include <fmt/format.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <span>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace fountain::domain {

// Wraps its own duplicate of MPI_COMM_WORLD, so the engine's messages never meet anyone
// else's. Collectives are called by one thread at a time (the engine's step, or a task that
// every other task of its kind waits for); point-to-point calls may come from any worker
// thread at once (MPI is initialised with MPI_THREAD_MULTIPLE).
class RankExchange {
 public:
  using Buffer = std::vector<char>;

  // The ranks of this run, or null when the process runs alone (MPI not started by a
  // launcher, one rank, or a build without MPI).
  static std::unique_ptr<RankExchange> world();
  // This process's place among the ranks on its node (shared memory): {local rank, local
  // ranks}; {0, 1} when it runs alone.
  struct NodePlace {
    int rank = 0, ranks = 1;
  };
  static NodePlace node_place();
  ~RankExchange();
  RankExchange(const RankExchange&) = delete;
  RankExchange& operator=(const RankExchange&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }

  bool any(bool local) const;
  long long sum(long long local) const;
  // Every rank's buffer, indexed by rank (this rank's own included): views into storage
  // kept and reused by the exchange, valid until its next allgather.
  std::vector<std::span<const char>> allgather(std::span<const char> mine) const;
  // The same for values: every rank's `mine`, indexed by rank, each as long as this rank's
  // (ranks that disagree on the length are a logic error, named by `what`).
  template <class T>
  std::vector<std::vector<T>> allgather_values(std::span<const T> mine, const char* what) const;
  // Every rank's `mine`, of whatever length each (a whole number of T).
  template <class T>
  std::vector<std::vector<T>> allgather_lists(std::span<const T> mine, const char* what) const;
  // Each rank's buffer `to[q]` goes to rank q alone (this rank's own is skipped): what every
  // rank sent to this one, indexed by sender, as views valid until the next alltoall.
  std::vector<std::span<const char>> alltoall(const std::vector<Buffer>& to) const;
  // The same from one buffer that holds the messages to ranks 0, 1, ... end to end, sizes[q]
  // bytes each (this rank's own empty): MPI sends from it directly, with no copy.
  std::vector<std::span<const char>> alltoall(std::span<const char> packed, std::span<const std::size_t> sizes) const;

  // Point to point: receives are posted before the tasks that need them run (their handle
  // is an index), sends are posted by tasks and completed together once the graph is done.
  int post_recv(int source, int tag, std::size_t bytes);
  // Non-blocking, one test for many: appends to `arrived` the positions in `handles` of
  // those whose message is in.
  void test_recvs(std::span<const int> handles, std::vector<int>& arrived);
  const Buffer& wait_recv(int handle);   // blocks until it has
  void post_send(int dest, int tag, Buffer data);
  void finish();                         // waits for every send, forgets every receive

  // Between graphs (no point-to-point message in flight): one message to `dest`, returning
  // once its buffer may be reused, and the next message from `source`, blocking until it is
  // in (a view valid until the next receive). Messages from one sender arrive in the order sent.
  void send(int dest, std::span<const char> data);
  std::span<const char> receive(int source);

  // Counted since the last reset: point-to-point and collective payload, sent by this rank.
  struct Traffic {
    std::uint64_t bytes = 0, messages = 0;
    std::uint64_t point_to_point_bytes = 0;  // of which by post_send (the rest by collectives)
  };
  Traffic traffic() const;
  // Frees the buffers the collectives and receive() keep for reuse (after an exchange far
  // larger than the run's usual ones, which would otherwise hold its memory to the end).
  void release_buffers();
  // Frees only those of alltoall (its packed sends and what it received).
  void release_alltoall_buffers();
  void reset_traffic();

 private:
  RankExchange() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int rank_ = 0, size_ = 1;
  mutable std::mutex mutex_;  // guards the send list and the traffic counts
  mutable Traffic traffic_;
  mutable std::vector<char> gathered_;  // reused by allgather, so large exchanges do not fault in fresh pages
  mutable std::vector<char> scattered_;  // reused by alltoall, likewise
  mutable std::vector<char> sending_;    // alltoall's contiguous send buffer, likewise
  Buffer received_;                      // receive()'s, likewise
};

template <class T>
std::vector<std::vector<T>> RankExchange::allgather_values(std::span<const T> mine, const char* what) const {
  static_assert(std::is_trivially_copyable_v<T>);
  const auto all = allgather(std::span<const char>(reinterpret_cast<const char*>(mine.data()), mine.size_bytes()));
  std::vector<std::vector<T>> out(all.size(), std::vector<T>(mine.size()));
  for (std::size_t r = 0; r < all.size(); ++r) {
    if (all[r].size() != mine.size_bytes())
      throw std::logic_error(fmt::format("rank {} sent {} bytes of {}, this rank {}", r, all[r].size(), what, mine.size_bytes()));
    if (!mine.empty()) std::memcpy(out[r].data(), all[r].data(), mine.size_bytes());
  }
  return out;
}

template <class T>
std::vector<std::vector<T>> RankExchange::allgather_lists(std::span<const T> mine, const char* what) const {
  static_assert(std::is_trivially_copyable_v<T>);
  const auto all = allgather(std::span<const char>(reinterpret_cast<const char*>(mine.data()), mine.size_bytes()));
  std::vector<std::vector<T>> out(all.size());
  for (std::size_t r = 0; r < all.size(); ++r) {
    if (all[r].size() % sizeof(T) != 0)
      throw std::logic_error(fmt::format("rank {} sent {} bytes of {}, not whole records", r, all[r].size(), what));
    out[r].resize(all[r].size() / sizeof(T));
    if (!out[r].empty()) std::memcpy(out[r].data(), all[r].data(), all[r].size());
  }
  return out;
}

}  // namespace fountain::domain
