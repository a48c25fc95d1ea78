#include "domain/RankExchange.hpp"

#include <cstring>
#include <deque>
#include <stdexcept>

#include "tasks/MpiSession.hpp"

#ifdef FOUNTAIN_HAVE_MPI
#include <mpi.h>
#endif

namespace fountain::domain {

#ifdef FOUNTAIN_HAVE_MPI
struct RankExchange::Impl {
  MPI_Comm comm = MPI_COMM_NULL;
  struct Pending {
    MPI_Request request = MPI_REQUEST_NULL;
    Buffer data;
    bool done = false;
  };
  std::deque<Pending> recvs;  // a deque: handles stay valid while more are posted
  std::deque<Pending> sends;
};

namespace {
void check(int err, const char* what) {
  if (err != MPI_SUCCESS) throw std::runtime_error(std::string("MPI call failed: ") + what);
}
int as_count(std::size_t n) {
  if (n > static_cast<std::size_t>(INT32_MAX)) throw std::runtime_error("MPI message over 2 GiB");
  return static_cast<int>(n);
}
}  // namespace

std::unique_ptr<RankExchange> RankExchange::world() {
  const int size = tasks::MpiSession::world_size();
  if (size < 2) return nullptr;
  std::unique_ptr<RankExchange> r(new RankExchange());
  r->impl_ = std::make_unique<Impl>();
  MPI_Comm_dup(MPI_COMM_WORLD, &r->impl_->comm);
  MPI_Comm_rank(r->impl_->comm, &r->rank_);
  r->size_ = size;
  return r;
}

RankExchange::NodePlace RankExchange::node_place() {
  int ready = 0;
  MPI_Initialized(&ready);
  if (!ready) return {};
  MPI_Comm node = MPI_COMM_NULL;
  check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node), "MPI_Comm_split_type");
  NodePlace place;
  MPI_Comm_rank(node, &place.rank);
  MPI_Comm_size(node, &place.ranks);
  MPI_Comm_free(&node);
  return place;
}

RankExchange::~RankExchange() {
  if (!impl_) return;
  int finalised = 0;
  MPI_Finalized(&finalised);
  if (finalised) return;
  for (auto& p : impl_->recvs)
    if (!p.done && p.request != MPI_REQUEST_NULL) {
      MPI_Cancel(&p.request);
      MPI_Request_free(&p.request);
    }
  for (auto& p : impl_->sends)
    if (p.request != MPI_REQUEST_NULL) MPI_Request_free(&p.request);
  MPI_Comm_free(&impl_->comm);
}

bool RankExchange::any(bool local) const {
  int in = local ? 1 : 0, out = 0;
  check(MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_LOR, impl_->comm), "Allreduce(any)");
  return out != 0;
}

long long RankExchange::sum(long long local) const {
  long long out = 0;
  check(MPI_Allreduce(&local, &out, 1, MPI_LONG_LONG, MPI_SUM, impl_->comm), "Allreduce(sum)");
  return out;
}

std::vector<std::span<const char>> RankExchange::allgather(std::span<const char> mine) const {
  const int n = size_;
  long long my_size = static_cast<long long>(mine.size());
  std::vector<long long> sizes(static_cast<std::size_t>(n));
  check(MPI_Allgather(&my_size, 1, MPI_LONG_LONG, sizes.data(), 1, MPI_LONG_LONG, impl_->comm), "Allgather(sizes)");
  std::vector<int> counts(static_cast<std::size_t>(n)), offsets(static_cast<std::size_t>(n));
  std::size_t total = 0;
  for (std::size_t r = 0; r < static_cast<std::size_t>(n); ++r) {
    counts[r] = as_count(static_cast<std::size_t>(sizes[r]));
    offsets[r] = as_count(total);
    total += static_cast<std::size_t>(sizes[r]);
  }
  if (gathered_.size() < total) gathered_.resize(total);
  check(MPI_Allgatherv(mine.data(), as_count(mine.size()), MPI_BYTE, gathered_.data(), counts.data(), offsets.data(),
                       MPI_BYTE, impl_->comm),
        "Allgatherv");
  std::vector<std::span<const char>> out(static_cast<std::size_t>(n));
  for (std::size_t r = 0; r < static_cast<std::size_t>(n); ++r)
    out[r] = std::span<const char>(gathered_.data() + offsets[r], static_cast<std::size_t>(counts[r]));
  std::lock_guard lock(mutex_);
  traffic_.bytes += mine.size() * static_cast<std::size_t>(n - 1);
  traffic_.messages += static_cast<std::uint64_t>(n - 1);
  return out;
}

std::vector<std::span<const char>> RankExchange::alltoall(const std::vector<Buffer>& to) const {
  const auto n = static_cast<std::size_t>(size_);
  if (to.size() != n) throw std::logic_error("alltoall needs one buffer per rank");
  // MPI wants one contiguous send buffer (kept, like the receiving one, so that it is not
  // zero-filled again at every exchange).
  std::vector<std::size_t> sizes(n, 0);
  std::size_t total = 0;
  for (std::size_t r = 0; r < n; ++r)
    if (r != static_cast<std::size_t>(rank_)) total += sizes[r] = to[r].size();
  if (sending_.size() < total) sending_.resize(total);
  std::size_t at = 0;
  for (std::size_t r = 0; r < n; ++r) {
    if (sizes[r] > 0) std::memcpy(sending_.data() + at, to[r].data(), sizes[r]);
    at += sizes[r];
  }
  return alltoall(std::span<const char>(sending_.data(), total), sizes);
}

std::vector<std::span<const char>> RankExchange::alltoall(std::span<const char> packed,
                                                          std::span<const std::size_t> sizes) const {
  const auto n = static_cast<std::size_t>(size_);
  if (sizes.size() != n || sizes[static_cast<std::size_t>(rank_)] != 0)
    throw std::logic_error("alltoall needs one size per rank, this rank's 0");
  std::vector<long long> out_sizes(n), in_sizes(n);
  for (std::size_t r = 0; r < n; ++r) out_sizes[r] = static_cast<long long>(sizes[r]);
  check(MPI_Alltoall(out_sizes.data(), 1, MPI_LONG_LONG, in_sizes.data(), 1, MPI_LONG_LONG, impl_->comm),
        "Alltoall(sizes)");
  std::vector<int> send_counts(n), send_offsets(n), recv_counts(n), recv_offsets(n);
  std::size_t out_total = 0, in_total = 0;
  for (std::size_t r = 0; r < n; ++r) {
    send_counts[r] = as_count(static_cast<std::size_t>(out_sizes[r]));
    send_offsets[r] = as_count(out_total);
    out_total += static_cast<std::size_t>(out_sizes[r]);
    recv_counts[r] = as_count(static_cast<std::size_t>(in_sizes[r]));
    recv_offsets[r] = as_count(in_total);
    in_total += static_cast<std::size_t>(in_sizes[r]);
  }
  if (out_total != packed.size()) throw std::logic_error("alltoall's sizes do not add up to its buffer");
  if (scattered_.size() < in_total) scattered_.resize(in_total);
  check(MPI_Alltoallv(packed.data(), send_counts.data(), send_offsets.data(), MPI_BYTE, scattered_.data(),
                      recv_counts.data(), recv_offsets.data(), MPI_BYTE, impl_->comm),
        "Alltoallv");
  std::vector<std::span<const char>> in(n);
  for (std::size_t r = 0; r < n; ++r)
    in[r] = std::span<const char>(scattered_.data() + recv_offsets[r], static_cast<std::size_t>(recv_counts[r]));
  std::lock_guard lock(mutex_);
  traffic_.bytes += out_total;
  for (std::size_t r = 0; r < n; ++r) traffic_.messages += send_counts[r] > 0 ? 1 : 0;
  return in;
}

int RankExchange::post_recv(int source, int tag, std::size_t bytes) {
  auto& p = impl_->recvs.emplace_back();
  p.data.resize(bytes);
  check(MPI_Irecv(p.data.data(), as_count(bytes), MPI_BYTE, source, tag, impl_->comm, &p.request), "Irecv");
  return static_cast<int>(impl_->recvs.size()) - 1;
}

void RankExchange::test_recvs(std::span<const int> handles, std::vector<int>& arrived) {
  std::vector<MPI_Request> requests;
  std::vector<int> position;  // in `handles`, of each request tested
  for (std::size_t k = 0; k < handles.size(); ++k) {
    auto& p = impl_->recvs[static_cast<std::size_t>(handles[k])];
    if (p.done) {
      arrived.push_back(static_cast<int>(k));
    } else {
      requests.push_back(p.request);
      position.push_back(static_cast<int>(k));
    }
  }
  if (requests.empty()) return;
  std::vector<int> indices(requests.size());
  int count = 0;
  check(MPI_Testsome(static_cast<int>(requests.size()), requests.data(), &count, indices.data(), MPI_STATUSES_IGNORE),
        "Testsome");
  if (count == MPI_UNDEFINED) return;
  for (int n = 0; n < count; ++n) {
    const int k = position[static_cast<std::size_t>(indices[static_cast<std::size_t>(n)])];
    auto& p = impl_->recvs[static_cast<std::size_t>(handles[static_cast<std::size_t>(k)])];
    p.request = MPI_REQUEST_NULL;
    p.done = true;
    arrived.push_back(k);
  }
}

const RankExchange::Buffer& RankExchange::wait_recv(int handle) {
  auto& p = impl_->recvs[static_cast<std::size_t>(handle)];
  if (!p.done) check(MPI_Wait(&p.request, MPI_STATUS_IGNORE), "Wait");
  p.done = true;
  return p.data;
}

void RankExchange::post_send(int dest, int tag, Buffer data) {
  std::lock_guard lock(mutex_);
  auto& p = impl_->sends.emplace_back();
  p.data = std::move(data);
  check(MPI_Isend(p.data.data(), as_count(p.data.size()), MPI_BYTE, dest, tag, impl_->comm, &p.request), "Isend");
  traffic_.bytes += p.data.size();
  traffic_.point_to_point_bytes += p.data.size();
  ++traffic_.messages;
}

namespace {
// The largest tag every MPI allows. Ghost messages use cell indices as tags, but none is in
// flight between graphs, so the two never meet.
constexpr int kBetweenGraphsTag = 32767;
}  // namespace

void RankExchange::send(int dest, std::span<const char> data) {
  check(MPI_Send(data.data(), as_count(data.size()), MPI_BYTE, dest, kBetweenGraphsTag, impl_->comm), "Send");
  std::lock_guard lock(mutex_);
  traffic_.bytes += data.size();
  traffic_.point_to_point_bytes += data.size();
  ++traffic_.messages;
}

std::span<const char> RankExchange::receive(int source) {
  MPI_Status status;
  check(MPI_Probe(source, kBetweenGraphsTag, impl_->comm, &status), "Probe");
  int bytes = 0;
  check(MPI_Get_count(&status, MPI_BYTE, &bytes), "Get_count");
  received_.resize(static_cast<std::size_t>(bytes));
  check(MPI_Recv(received_.data(), bytes, MPI_BYTE, source, kBetweenGraphsTag, impl_->comm, MPI_STATUS_IGNORE), "Recv");
  return received_;
}

void RankExchange::finish() {
  for (auto& p : impl_->sends) check(MPI_Wait(&p.request, MPI_STATUS_IGNORE), "Wait(send)");
  impl_->sends.clear();
  for (auto& p : impl_->recvs)
    if (!p.done) throw std::logic_error("a posted receive was never completed");
  impl_->recvs.clear();
}
#else
struct RankExchange::Impl {};
std::unique_ptr<RankExchange> RankExchange::world() { return nullptr; }
RankExchange::NodePlace RankExchange::node_place() { return {}; }
RankExchange::~RankExchange() = default;
namespace {
[[noreturn]] void no_mpi() { throw std::logic_error("built without MPI"); }
}  // namespace
bool RankExchange::any(bool) const { no_mpi(); }
long long RankExchange::sum(long long) const { no_mpi(); }
std::vector<std::span<const char>> RankExchange::allgather(std::span<const char>) const { no_mpi(); }
std::vector<std::span<const char>> RankExchange::alltoall(const std::vector<Buffer>&) const { no_mpi(); }
std::vector<std::span<const char>> RankExchange::alltoall(std::span<const char>, std::span<const std::size_t>) const {
  no_mpi();
}
int RankExchange::post_recv(int, int, std::size_t) { no_mpi(); }
void RankExchange::test_recvs(std::span<const int>, std::vector<int>&) { no_mpi(); }
const RankExchange::Buffer& RankExchange::wait_recv(int) { no_mpi(); }
void RankExchange::post_send(int, int, Buffer) { no_mpi(); }
void RankExchange::finish() { no_mpi(); }
void RankExchange::send(int, std::span<const char>) { no_mpi(); }
std::span<const char> RankExchange::receive(int) { no_mpi(); }
#endif

void RankExchange::release_buffers() {
  std::vector<char>().swap(gathered_);
  std::vector<char>().swap(scattered_);
  std::vector<char>().swap(sending_);
  Buffer().swap(received_);
}

void RankExchange::release_alltoall_buffers() {
  std::vector<char>().swap(scattered_);
  std::vector<char>().swap(sending_);
}

RankExchange::Traffic RankExchange::traffic() const {
  std::lock_guard lock(mutex_);
  return traffic_;
}

void RankExchange::reset_traffic() {
  std::lock_guard lock(mutex_);
  traffic_ = {};
}

}  // namespace fountain::domain
