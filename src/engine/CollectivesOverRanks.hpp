// The collectives of work spread over ranks (the gravity tree's assembly, the group finders) carried by the run's RankExchange.
#pragma once
#include <vector>

#include "domain/RankExchange.hpp"
#include "core/Collectives.hpp"

namespace fountain {

class CollectivesOverRanks : public Collectives {
 public:
  explicit CollectivesOverRanks(domain::RankExchange& ranks) : ranks_(ranks) {}
  int rank() const override { return ranks_.rank(); }
  int size() const override { return ranks_.size(); }
  std::vector<std::vector<char>> allgather(std::span<const char> mine) override {
    std::vector<std::vector<char>> out;
    for (const auto& m : ranks_.allgather(mine)) out.emplace_back(m.begin(), m.end());
    return out;
  }
  std::vector<std::vector<char>> alltoall(const std::vector<std::vector<char>>& to) override {
    std::vector<std::vector<char>> out;
    for (const auto& m : ranks_.alltoall(to)) out.emplace_back(m.begin(), m.end());
    return out;
  }

 private:
  domain::RankExchange& ranks_;
};

}  // namespace fountain
