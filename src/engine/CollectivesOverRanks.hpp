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
  // The gravity tree's parts are a step's largest messages (megabytes a rank): each buffer is
  // freed once packed, the packed one once sent, and the exchange's own buffers once copied
  // out, so that no stage holds them twice and none outlives the call.
  std::vector<std::vector<char>> alltoall(std::vector<std::vector<char>> to) override {
    std::vector<std::size_t> sizes(to.size(), 0);
    std::size_t total = 0;
    for (std::size_t q = 0; q < to.size(); ++q)
      if (static_cast<int>(q) != rank()) total += sizes[q] = to[q].size();
    std::vector<char> packed;
    packed.reserve(total);
    for (std::size_t q = 0; q < to.size(); ++q) {
      if (static_cast<int>(q) != rank()) packed.insert(packed.end(), to[q].begin(), to[q].end());
      std::vector<char>().swap(to[q]);
    }
    std::vector<std::vector<char>> out;
    {
      const auto in = ranks_.alltoall(std::span<const char>(packed), sizes);
      std::vector<char>().swap(packed);
      for (const auto& m : in) out.emplace_back(m.begin(), m.end());
    }
    ranks_.release_alltoall_buffers();
    return out;
  }

 private:
  domain::RankExchange& ranks_;
};

}  // namespace fountain
