// `fountain ic`: checks the options of a validation problem's initial conditions, then writes them.
#pragma once
#include <cstddef>
#include <string>

#include "ics/CosmologicalBox.hpp"
#include "ics/RotatingSphere.hpp"

namespace fountain {

struct IcRequest {
  std::string problem;      // sod | sedov | gresho | evrard | sphere | cosmo
  std::string output;       // HDF5 file to write
  int resolution = 0;       // 0: the problem's default
  bool resolution_given = false;
  double gamma = 5.0 / 3.0;
  ics::RotatingSphereParams sphere;
  ics::CosmologicalBoxParams cosmo;  // its level is set from the resolution
};

// The particle count a request makes (estimated from the lattice, before anything is built).
double ic_particle_count(const IcRequest& r);

// Bytes the generator needs per particle: every particle field plus the lattice and the
// buffers of the HDF5 writer.
std::size_t ic_bytes_per_particle();

// Memory this process may still take, in bytes (MemAvailable, else the physical memory).
double available_memory_bytes();

// Throws InputError naming the option for a value no problem can use (a non-positive
// resolution, an adiabatic index that is not a finite number above 1, ...) or for a size whose
// estimated memory exceeds `memory_bytes`.
void check_ic_request(const IcRequest& r, double memory_bytes);

// Checks the request against this machine's memory, builds the particles and writes them;
// returns the line to print.
std::string write_ic(const IcRequest& r);

}  // namespace fountain
