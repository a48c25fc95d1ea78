// Ranks run as threads in one process, for tests of work spread over ranks (core/Collectives.hpp).
#pragma once
#include <barrier>
#include <exception>
#include <functional>
#include <span>
#include <thread>
#include <vector>

#include "core/Collectives.hpp"

namespace fountain::test_ranks {

// R ranks as R threads: each collective meets at a barrier, reads every rank's slot, and
// meets again before the slots are reused.
class ThreadRanks {
 public:
  explicit ThreadRanks(int ranks)
      : ranks_(ranks), barrier_(ranks), slots_(static_cast<std::size_t>(ranks)),
        mail_(static_cast<std::size_t>(ranks), std::vector<std::vector<char>>(static_cast<std::size_t>(ranks))) {}

  class Messages : public Collectives {
   public:
    Messages(ThreadRanks& all, int rank) : all_(all), rank_(rank) {}
    int rank() const override { return rank_; }
    int size() const override { return all_.ranks_; }
    std::vector<std::vector<char>> allgather(std::span<const char> mine) override {
      all_.slots_[static_cast<std::size_t>(rank_)].assign(mine.begin(), mine.end());
      all_.barrier_.arrive_and_wait();
      std::vector<std::vector<char>> out = all_.slots_;
      all_.barrier_.arrive_and_wait();
      return out;
    }
    std::vector<std::vector<char>> alltoall(std::vector<std::vector<char>> to) override {
      for (int q = 0; q < all_.ranks_; ++q)
        if (q != rank_) all_.mail_[static_cast<std::size_t>(q)][static_cast<std::size_t>(rank_)] = to[static_cast<std::size_t>(q)];
      all_.barrier_.arrive_and_wait();
      std::vector<std::vector<char>> out = all_.mail_[static_cast<std::size_t>(rank_)];
      all_.barrier_.arrive_and_wait();
      return out;
    }

   private:
    ThreadRanks& all_;
    int rank_;
  };

  // Runs body(messages) on every rank at once; the first exception is rethrown.
  void run(const std::function<void(Messages&)>& body) {
    std::vector<std::thread> threads;
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(ranks_));
    for (int r = 0; r < ranks_; ++r)
      threads.emplace_back([&, r] {
        Messages m(*this, r);
        try {
          body(m);
        } catch (...) {
          errors[static_cast<std::size_t>(r)] = std::current_exception();
          barrier_.arrive_and_drop();
        }
      });
    for (auto& t : threads) t.join();
    for (auto& e : errors)
      if (e) std::rethrow_exception(e);
  }

 private:
  int ranks_;
  std::barrier<> barrier_;
  std::vector<std::vector<char>> slots_;
  std::vector<std::vector<std::vector<char>>> mail_;  // mail_[to][from]
};

}  // namespace fountain::test_ranks
