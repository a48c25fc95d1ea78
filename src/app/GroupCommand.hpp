// `fountain fof` and `fountain hop`: a snapshot's groups, written as catalogues.
#pragma once
#include <span>
#include <string>
#include <vector>

#include "core/Collectives.hpp"
#include "io/GroupFiles.hpp"

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
// The same for particles that several ranks hold, each its own `mine` (as a run finds them at
// its outputs); `header` gives the snapshot's time, box, cosmology and units (its particles
// are not read), `request.snapshot` the name the catalogue records. Every rank calls it; rank
// 0 writes the catalogue and returns the line, the others an empty string. The catalogue is
// the one `fountain fof` writes from the snapshot of the same particles.
std::string find_groups(const FofRequest& request, const groups::ParticleSet& mine, const io::GroupInput& header,
                        Collectives* ranks);

struct HopRequest {
  std::string snapshot;
  std::string output;
  double outer = 80.0;          // delta_outer in mean baryon densities (the paper's)
  double saddle_factor = 2.5;   // delta_saddle / delta_outer
  double peak_factor = 3.0;     // delta_peak / delta_outer
  int n_dens = 64, n_hop = 16, n_merge = 4;
  double omega_b = -1.0;        // >= 0: instead of the snapshot's OmegaBaryon
  int threads = 0;
};

// HOP on the snapshot's baryons (gas with its hidden stars, and stars); writes the catalogue
// and returns the summary line.
std::string find_hop_groups(const HopRequest& request);
// The same for baryons that several ranks hold, each its own (types 0 and 4, with the gas's
// hidden stellar masses), as a run finds them at its outputs; `header` as for find_groups.
// Every rank calls it; rank 0 writes the catalogue and returns the line, the others an empty
// string. The catalogue is the one `fountain hop` writes from the snapshot of the same particles.
std::string find_hop_groups(const HopRequest& request, const groups::ParticleSet& baryons, std::span<const double> hidden,
                            const io::GroupInput& header, Collectives* ranks);

}  // namespace fountain
