// The group finders' files: a snapshot's particles of every type in, a group catalogue (GADGET-4's names) out.
#pragma once
#include <string>
#include <vector>

#include "core/Units.hpp"
#include "groups/FofAcrossRanks.hpp"
#include "groups/FofCatalogue.hpp"
#include "groups/Hop.hpp"
#include "groups/HopAcrossRanks.hpp"

namespace fountain::io {

// A snapshot (or initial conditions) in the GADGET HDF5 layout, as the group finders read it.
struct GroupInput {
  groups::ParticleSet particles;      // every type 0-5; velocities peculiar (cosmological files:
                                      // the file's v_pec / sqrt(a) times sqrt(a))
  std::vector<double> hidden_mass;    // per particle: gas's HiddenStellarMasses, 0 for the rest
  double box = 0.0;                   // BoxSize (comoving)
  double time = 0.0;                  // Time: a in cosmological files
  bool cosmological = false;          // the header gives Omega0, OmegaLambda and HubbleParam, Omega0 > 0
  double omega_m = 0.0, omega_lambda = 0.0, hubble_param = 1.0;
  double omega_b = -1.0;              // OmegaBaryon, or -1 where the header lacks it
  Units units;                        // the file's /Units, else Fountain's default (h-scaled) units
};

// Reads every particle type's Coordinates, Velocities, ParticleIDs and Masses (or the
// MassTable). A missing or malformed file, dataset or attribute, a count that disagrees with
// the header, a snapshot split over several files, or a non-finite position throws InputError
// naming the file and the dataset.
GroupInput read_group_input(const std::string& path);

// What a catalogue records about how it was made.
struct FofCatalogueInfo {
  std::string snapshot;
  double linking_length = 0.0, b = 0.0;
  std::size_t min_members = 0;
  std::vector<int> linking_types;
  double overdensity = 0.0;  // the mean density within R_200 (internal units, comoving)
};

// /Header (counts, the snapshot's time, cosmology and units from `header`, whose particles are
// not read; how the groups were found), /Group (GroupLen, GroupLenType, GroupMass,
// GroupMassType, GroupCM, GroupPos = the potential minimum, GroupVel, Group_M_Crit200,
// Group_R_Crit200, GroupOffset) and /IDs (ID and Type of the members, group by group, each
// group's by type then ID).
void write_fof_catalogue(const std::string& path, const groups::GroupCatalogue& catalogue, const GroupInput& header,
                         const FofCatalogueInfo& info);

// What a zoom or a mass function needs of a friends-of-friends catalogue: each group's centre,
// FOF mass and M_200, R_200, and the snapshot's box, time, cosmology and units (a header
// without OmegaBaryon gives -1; one without units, Fountain's defaults).
struct FofHalos {
  std::vector<Vec3> centre;  // GroupPos
  std::vector<double> mass, m200, r200;
  double box = 0.0, time = 0.0;
  double omega_m = 0.0, omega_lambda = 0.0, hubble_param = 1.0, omega_b = -1.0;
  Units units;
};
// Reads them; a missing or malformed file or dataset throws InputError naming it.
FofHalos read_fof_halos(const std::string& path);

// How a HOP catalogue was made.
struct HopCatalogueInfo {
  std::string snapshot;
  groups::HopParameters parameters;
  double mean_baryon_density = 0.0;  // the thresholds' unit (comoving)
};

// /Header (counts, the snapshot's time, cosmology and units from `header`, HOP's parameters
// and thresholds), /Group (GroupLen, GroupLenType, GroupMass, GroupMassType with hidden
// stellar mass under type 4, GroupCM, GroupPeakPos, GroupPeakDensity, GroupVel, GroupOffset)
// and /IDs (ID, Type and the HOP Density of the members, group by group in increasing ID).
void write_hop_catalogue(const std::string& path, const groups::HopCatalogue& catalogue, const GroupInput& header,
                         const HopCatalogueInfo& info);

}  // namespace fountain::io
