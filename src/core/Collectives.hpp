// The collectives that work spread over ranks needs (the gravity tree's assembly, the group finders), independent of MPI.
#pragma once
#include <span>
#include <vector>

namespace fountain {

// Every rank calls each collective, in the same order. The engine's RankExchange provides
// them for MPI runs (CollectivesOverRanks); tests run ranks as threads.
class Collectives {
 public:
  virtual ~Collectives() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // Every rank's buffer, indexed by rank (this rank's own included).
  virtual std::vector<std::vector<char>> allgather(std::span<const char> mine) = 0;
  // to[q] goes to rank q (this rank's own is not sent): what each rank sent to this one. The
  // buffers are taken, so that an implementation can free each once it is sent.
  virtual std::vector<std::vector<char>> alltoall(std::vector<std::vector<char>> to) = 0;
};

}  // namespace fountain
