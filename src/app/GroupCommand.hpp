// `fountain fof`: friends-of-friends groups of a snapshot, written as a catalogue.
#pragma once
#include <string>
#include <vector>

namespace fountain {

struct FofRequest {
  std::string snapshot;
  std::string output;
  double b = 0.2;                   // linking length in mean spacings of the primaries
  double linking_length = 0.0;      // > 0: this comoving length instead
  std::vector<int> linking_types{1};
  std::size_t min_members = 32;
  int threads = 0;                  // 0: all cores
};

// Finds the groups and writes the catalogue; returns the summary line.
std::string find_groups(const FofRequest& request);

}  // namespace fountain
