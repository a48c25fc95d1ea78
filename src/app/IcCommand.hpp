// `fountain ic`: checks the options of a validation problem's initial conditions, then writes them.
#pragma once
#include <cstddef>
#include <string>

#include "ics/CosmologicalBox.hpp"
#include "ics/RotatingSphere.hpp"
#include "ics/ZoomInitialConditions.hpp"
#include "io/InitialConditions.hpp"

namespace fountain {

struct IcRequest {
  std::string problem;      // sod | sedov | gresho | evrard | sphere | cosmo | zoom
  std::string output;       // HDF5 file to write
  int resolution = 0;       // 0: the problem's default
  bool resolution_given = false;
  double gamma = 5.0 / 3.0;
  ics::RotatingSphereParams sphere;
  ics::CosmologicalBoxParams cosmo;  // its level is set from the resolution
  // zoom: the levels; without a parent run, the parent run's initial conditions.
  struct Zoom {
    ics::ZoomLevels levels;
    std::string parent;               // the parent run's snapshot at z = 0
    std::string groups;               // its friends-of-friends catalogue
    long long halo = -1;              // >= 0: this group; else chosen by mass and isolation
    double mass_min = 6e11, mass_max = 1.5e12;  // M_200 range of candidates (Msun/h)
    double isolation = 2.0;           // no group of half the mass within this (Mpc/h, comoving)
    double target = 6300;             // high-resolution particles per species wanted
    double mass_scale = 1.0;          // != 1: the zoom scaled to masses x this (the paper's MFB/100)
  } zoom;
};

// The particle count a request makes (estimated from the lattice, before anything is built).
double ic_particle_count(const IcRequest& r);

// Bytes the generator of `problem` needs per particle: every particle field plus the lattice
// and the buffers of the HDF5 writer; for cosmo and zoom, the lean stores' fields and the grids.
std::size_t ic_bytes_per_particle(const std::string& problem);

// Memory this process may still take, in bytes (MemAvailable, else the physical memory).
double available_memory_bytes();

// Throws InputError naming the option for a value no problem can use (a non-positive
// resolution, an adiabatic index that is not a finite number above 1, ...) or for a size whose
// estimated memory exceeds `memory_bytes`.
void check_ic_request(const IcRequest& r, double memory_bytes);

// Checks the request against this machine's memory, builds the particles and writes them;
// returns the line to print.
std::string write_ic(const IcRequest& r);

// What a cosmological or zoom file records of how it was made (its /Cosmology group): the
// generator, seed, spectrum, perturbation order and pairing, and the zoom's levels.
io::CosmologicalIcInfo cosmological_ic_info(const IcRequest& r, const ics::CosmologicalBoxParams& c, double a,
                                            const Units& units);

// `fountain ic zoom` (ZoomCommand.cpp): the parent run's initial conditions, or with a parent
// run and its groups, a zoom on one of its halos (COSMOLOGY.md C8).
std::string write_zoom_ic(const IcRequest& r);

}  // namespace fountain
