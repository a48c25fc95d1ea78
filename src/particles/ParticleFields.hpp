// The table of particle fields: each field's names, units and description, and where it is written and sent.
//
// Snapshots, restart files, the MPI messages between ranks and the user guide's list of
// snapshot datasets all come from these two tables; the stores' resize, for_each_field and
// permute walk them too. A new field is its member in the store plus one row here (and the code
// that computes it); tests/test_particle_fields.cpp checks that each field reaches the files and
// messages its row names. The order of the rows is the order of the fields in every message
// and in restart files: reordering rows changes the message layouts and the restart format
// (io/RestartFile.hpp's version).
#pragma once
#include <cstddef>
#include <tuple>
#include <type_traits>
#include <vector>

#include "particles/CollisionlessParticles.hpp"
#include "particles/FieldInfo.hpp"
#include "particles/GasParticles.hpp"

namespace fountain {

namespace field_units {
inline constexpr Dimensions kNumber{};
inline constexpr Dimensions kMass{.mass = 1};
inline constexpr Dimensions kLength{.length = 1, .a = 1};
inline constexpr Dimensions kInverseLength{.length = -1, .a = -1};
inline constexpr Dimensions kTime{.time = 1};
inline constexpr Dimensions kRate{.time = -1, .a = -1};  // velocity gradients
inline constexpr Dimensions kVelocity{.length = 1, .time = -1};
inline constexpr Dimensions kAcceleration{.length = 1, .time = -2};
inline constexpr Dimensions kDensity{.mass = 1, .length = -3, .a = -3};
inline constexpr Dimensions kEnergy{.mass = 1, .length = 2, .time = -2};
inline constexpr Dimensions kSpecificEnergy{.length = 2, .time = -2, .a_gamma_minus_1 = -3};
inline constexpr Dimensions kSpecificEnergyRate{.length = 2, .time = -3, .a_gamma_minus_1 = -3};
inline constexpr Dimensions kSoundSpeed{.length = 1, .time = -1, .a_gamma_minus_1 = -1.5};
inline constexpr Dimensions kPotential{.length = 2, .time = -2, .a = -1};  // SWIFT: potentials scale as 1/a
inline constexpr Dimensions kSphAlphaDependent{.depends_on_parameters = true};
inline constexpr Dimensions kGammaDependent{.depends_on_parameters = true};
}  // namespace field_units

// clang-format off
inline constexpr auto kGasFields = [] {
  using namespace field_units;
  using namespace message;
  using G = GasParticles;
  constexpr auto always = InSnapshots::always, with_star_formation = InSnapshots::with_star_formation;
  // Set when a particle is made and never changed by a step: not in the step's state. Changed
  // by a step (star formation, feedback, gravity, integration): in every state sync.
  constexpr Messages kMadeOnce = whole_state | migration, kStepped = whole_state | step_state | migration;
  return std::tuple{
    // Identity and conserved state.
    field(&G::id, {.key = "id", .name = "ParticleIDs", .units = kNumber,
                   .description = "Unique IDs of the particles",
                   .snapshot = always, .messages = kMadeOnce}),
    field(&G::mass, {.key = "mass", .name = "Masses", .units = kMass,
                     .description = "Masses of the particles",
                     .snapshot = always, .messages = kStepped | halo_star_formation | star_formation_event}),
    // Hybrid gas/star state.
    field(&G::mass_initial, {.key = "mass_initial", .name = "InitialMasses", .units = kMass,
                             .description = "Gas masses at the start (thresholds for spawning and dissolving)",
                             .snapshot = with_star_formation, .messages = kMadeOnce}),
    field(&G::mass_stars_hidden, {.key = "mass_stars_hidden", .name = "HiddenStellarMasses", .units = kMass,
                                  .description = "Stellar mass formed by the particle and not yet spawned (counts for gravity and inertia only)",
                                  .snapshot = with_star_formation, .messages = kStepped | halo_star_formation | star_formation_event}),
    field(&G::reservoir, {.key = "reservoir", .name = "FeedbackReservoir", .units = kEnergy,
                          .description = "Cold-phase feedback energy held until the particle can be promoted to the hot phase",
                          .snapshot = with_star_formation, .messages = kStepped | star_formation_event}),
    field(&G::promoted, {.key = "promoted", .name = "Promoted", .units = kNumber,
                         .description = "1 if the particle was promoted to the hot phase by feedback",
                         .snapshot = with_star_formation, .messages = kStepped}),
    field(&G::promotion_time, {.key = "promotion_time", .name = "PromotionTime", .units = kTime,
                               .description = "Time of the last promotion (-1: never)",
                               .snapshot = with_star_formation, .messages = kStepped}, -1.0),
    field(&G::feedback_hot_energy, {.key = "feedback_hot_energy", .name = "FeedbackHotEnergy", .units = kEnergy,
                                    .description = "Feedback energy this step's star formation gives the hot neighbours",
                                    .messages = kStepped}),
    field(&G::x, {.key = "x", .name = "Coordinates", .units = kLength,
                  .description = "Positions of the particles",
                  .snapshot = always, .messages = kMadeOnce}),
    field(&G::v_full, {.key = "v_full", .name = "IntegratedVelocities", .units = kVelocity,
                       .description = "Integrated velocities of the particles (half a step ahead after a first kick)",
                       .messages = kStepped | halo_after_ghost | star_formation_event}),
    field(&G::u_full, {.key = "u_full", .name = "IntegratedInternalEnergy", .units = kSpecificEnergy,
                       .description = "Integrated specific internal energies of the particles",
                       .messages = kStepped | halo_after_ghost | star_formation_event}),
    // Predicted state: drifted to the current time, what neighbours read.
    field(&G::v, {.key = "v", .name = "Velocities", .units = kVelocity,
                  .description = "Velocities of the particles (predicted)",
                  .snapshot = always, .messages = kStepped | halo_after_ghost | star_formation_event}),
    field(&G::u, {.key = "u", .name = "InternalEnergy", .units = kSpecificEnergy,
                  .description = "Specific internal energies of the particles (predicted)",
                  .snapshot = always, .messages = kStepped | halo_after_ghost | star_formation_event}),
    field(&G::h, {.key = "h", .name = "SmoothingLength", .units = kLength,
                  .description = "Smoothing lengths (compact support radius of the kernel) of the particles",
                  .snapshot = always, .messages = kStepped | ghost_density}),
    field(&G::rho, {.key = "rho", .name = "Density", .units = kDensity,
                    .description = "SPH densities of the particles",
                    .snapshot = always, .messages = kStepped | ghost_density}),
    // The MSPH rule's density and h as predicted at the start of the step.
    field(&G::rho_msph, {.key = "rho_msph", .name = "MsphDensity", .units = kDensity,
                         .description = "Densities of the particles as predicted at the start of the step (what the MSPH rule reads)",
                         .derived = true, .messages = kStepped}),
    field(&G::h_msph, {.key = "h_msph", .name = "MsphSmoothingLength", .units = kLength,
                       .description = "Smoothing lengths of the particles as predicted at the start of the step (what the MSPH rule reads)",
                       .derived = true, .messages = kStepped}),
    // Density-loop accumulators and results.
    field(&G::wcount, {.key = "wcount", .name = "NeighbourNumber", .units = kNumber,
                       .description = "Kernel-weighted neighbour numbers (4 pi / 3) h^3 sum W of the particles",
                       .snapshot = always, .messages = kStepped | ghost_density}),
    field(&G::wcount_dh, {.key = "wcount_dh", .name = "NeighbourNumberDerivative", .units = kInverseLength,
                          .description = "Derivatives of the weighted neighbour numbers with respect to h",
                          .messages = kStepped | ghost_density}),
    field(&G::div_v, {.key = "div_v", .name = "VelocityDivergence", .units = kRate,
                      .description = "SPH velocity divergences of the particles",
                      .messages = kStepped | ghost_density}),
    field(&G::curl_v, {.key = "curl_v", .name = "VelocityCurl", .units = kRate,
                       .description = "SPH velocity curls of the particles",
                       .messages = kStepped | ghost_density}),
    field(&G::strain_diagonal, {.key = "strain_diagonal", .name = "StrainRateDiagonal", .units = kRate,
                                .description = "Diagonal of the symmetric part of the velocity gradients (S_xx, S_yy, S_zz; zero without hydro.viscosity_reconstruction)",
                                .messages = kStepped | ghost_density}),
    field(&G::strain_shear, {.key = "strain_shear", .name = "StrainRateShear", .units = kRate,
                             .description = "Off-diagonal entries of the symmetric part of the velocity gradients (S_xy, S_xz, S_yz; zero without hydro.viscosity_reconstruction)",
                             .messages = kStepped | ghost_density}),
    // Prepared for the force loop from the predicted state.
    field(&G::soundspeed, {.key = "soundspeed", .name = "SoundSpeed", .units = kSoundSpeed,
                           .description = "Sound speeds sqrt(gamma (gamma - 1) u) of the particles",
                           .derived = true, .messages = kStepped | ghost_force_inputs}),
    field(&G::p_over_rho_a, {.key = "p_over_rho_a", .name = "PressureOverDensityToAlpha", .units = kSphAlphaDependent,
                             .description = "P / rho^alpha of the momentum equation (units M^(1-alpha) L^(3 alpha-1) t^-2, alpha = hydro.sph_alpha)",
                             .derived = true, .messages = kStepped | ghost_force_inputs}),
    field(&G::inv_rho_2ma, {.key = "inv_rho_2ma", .name = "InverseDensityToTwoMinusAlpha", .units = kSphAlphaDependent,
                            .description = "1 / rho^(2 - alpha) of the momentum equation (units M^(alpha-2) L^(6-3 alpha), alpha = hydro.sph_alpha)",
                            .derived = true, .messages = kStepped | ghost_force_inputs}),
    field(&G::balsara, {.key = "balsara", .name = "BalsaraSwitch", .units = kNumber,
                        .description = "Balsara switches of the particles",
                        .derived = true, .messages = kStepped | ghost_force_inputs}),
    field(&G::entropy, {.key = "entropy", .name = "EntropyFunction", .units = kGammaDependent,
                        .description = "Entropy functions P / rho^gamma of the particles (units M^(1-gamma) L^(3 gamma-1) t^-2; zero without hydro.viscosity_reconstruction)",
                        .derived = true, .messages = kStepped | ghost_force_inputs}),
    // Force-loop results.
    field(&G::a_hydro, {.key = "a_hydro", .name = "HydroAcceleration", .units = kAcceleration,
                        .description = "Hydrodynamic accelerations of the particles at the last force loop",
                        .messages = kStepped | halo_after_ghost}),
    field(&G::du_dt, {.key = "du_dt", .name = "InternalEnergyRate", .units = kSpecificEnergyRate,
                      .description = "Rates of change of the specific internal energies, radiative cooling included",
                      .messages = kStepped | halo_after_ghost | star_formation_event}),
    field(&G::du_dt_cool, {.key = "du_dt_cool", .name = "CoolingRate", .units = kSpecificEnergyRate,
                           .description = "The part of the rates of change of the specific internal energies that is radiative cooling",
                           .messages = kStepped | halo_after_ghost | star_formation_event}),
    field(&G::v_sig, {.key = "v_sig", .name = "MaxSignalVelocity", .units = kSoundSpeed,
                      .description = "Largest signal velocities over the force loop's pairs of the particles",
                      .messages = kStepped | halo_after_ghost}),
    // Gravity.
    field(&G::a_grav, {.key = "a_grav", .name = "GravAcceleration", .units = kAcceleration,
                       .description = "Gravitational accelerations of the particles at the last force computation (0 without gravity)",
                       .snapshot = always, .messages = kStepped | halo_gravity}),
    field(&G::potential, {.key = "potential", .name = "Potential", .units = kPotential,
                          .description = "Specific gravitational potentials of the particles at the last force computation (0 without gravity)",
                          .snapshot = always, .messages = kStepped}),
    field(&G::a_mesh, {.key = "a_mesh", .name = "MeshAcceleration", .units = kAcceleration,
                       .description = "The periodic mesh's (long-range) part of GravAcceleration, from the start of the mesh step",
                       .messages = kStepped | halo_mesh}),
    field(&G::potential_mesh, {.key = "potential_mesh", .name = "MeshPotential", .units = kPotential,
                               .description = "The periodic mesh's part of Potential, from the start of the mesh step",
                               .messages = kStepped}),
    // Time integration.
    field(&G::time_bin, {.key = "time_bin", .name = "TimeBin", .units = kNumber,
                         .description = "Time bins of the particles (step = 2^bin integer time units)",
                         .snapshot = always, .messages = kStepped | halo_after_ghost}),
    field(&G::ti_begin, {.key = "ti_begin", .name = "StepBegin", .units = kNumber,
                         .description = "Integer times at which the particles' current steps began",
                         .messages = kStepped | halo_after_ghost}),
    field(&G::courant_bin, {.key = "courant_bin", .name = "CourantTimeBin", .units = kNumber,
                            .description = "Time bins the Courant criterion alone allows the particles",
                            .derived = true, .messages = kStepped | ghost_bin}),
    field(&G::limit_bin, {.key = "limit_bin", .name = "LimiterTimeBin", .units = kNumber,
                          .description = "Neighbours' smallest time bins + 2 (the timestep limiter; 127: none)",
                          .messages = kStepped | halo_after_ghost}, kNoBin),
    // Any rank may ask to wake any particle: the engine combines the requests apart.
    field(&G::wake_bin, {.key = "wake_bin", .name = "WakeTimeBin", .units = kNumber,
                         .description = "Time bins active neighbours asked the particles to shorten their steps to (127: none)",
                         .messages = migration}, kNoBin),
  };
}();

inline constexpr auto kCollisionlessFields = [] {
  using namespace field_units;
  using namespace message;
  using C = CollisionlessParticles;
  constexpr auto always = InSnapshots::always, stars_only = InSnapshots::stars_only;
  // As for the gas: every field migrates with its particle at a recut (halo mode).
  constexpr Messages kMadeOnce = whole_state | migration, kStepped = whole_state | step_state | migration;
  return std::tuple{
    field(&C::id, {.key = "id", .name = "ParticleIDs", .units = kNumber,
                   .description = "Unique IDs of the particles",
                   .snapshot = always, .messages = kMadeOnce}),
    field(&C::species, {.key = "species", .name = "Species", .units = kNumber,
                        .description = "GADGET particle types of the particles (1: dark matter, 4: star)",
                        .messages = kMadeOnce}, Species::DarkMatter),
    field(&C::birth_time, {.key = "birth_time", .name = "BirthTime", .units = kTime,
                           .description = "Times the stars were spawned",
                           .snapshot = stars_only, .messages = kMadeOnce}),
    field(&C::parent_id, {.key = "parent_id", .name = "ParentID", .units = kNumber,
                          .description = "IDs of the gas particles that formed the stars",
                          .snapshot = stars_only, .messages = kMadeOnce}),
    field(&C::mass, {.key = "mass", .name = "Masses", .units = kMass,
                     .description = "Masses of the particles",
                     .snapshot = always, .messages = kMadeOnce}),
    field(&C::x, {.key = "x", .name = "Coordinates", .units = kLength,
                  .description = "Positions of the particles",
                  .snapshot = always, .messages = kMadeOnce}),
    field(&C::v_full, {.key = "v_full", .name = "IntegratedVelocities", .units = kVelocity,
                       .description = "Integrated velocities of the particles (half a step ahead after a first kick)",
                       .messages = kStepped}),
    field(&C::v, {.key = "v", .name = "Velocities", .units = kVelocity,
                  .description = "Velocities of the particles (predicted)",
                  .snapshot = always, .messages = kStepped}),
    field(&C::a_grav, {.key = "a_grav", .name = "Acceleration", .units = kAcceleration,
                       .description = "Gravitational accelerations of the particles at the last force computation",
                       .snapshot = always, .messages = kStepped}),
    field(&C::potential, {.key = "potential", .name = "Potential", .units = kPotential,
                          .description = "Specific gravitational potentials of the particles at the last force computation",
                          .snapshot = always, .messages = kStepped}),
    field(&C::a_mesh, {.key = "a_mesh", .name = "MeshAcceleration", .units = kAcceleration,
                       .description = "The periodic mesh's (long-range) part of Acceleration, from the start of the mesh step",
                       .messages = kStepped}),
    field(&C::potential_mesh, {.key = "potential_mesh", .name = "MeshPotential", .units = kPotential,
                               .description = "The periodic mesh's part of Potential, from the start of the mesh step",
                               .messages = kStepped}),
    field(&C::time_bin, {.key = "time_bin", .name = "TimeBin", .units = kNumber,
                         .description = "Time bins of the particles (step = 2^bin integer time units)",
                         .messages = kStepped}),
    field(&C::ti_begin, {.key = "ti_begin", .name = "StepBegin", .units = kNumber,
                         .description = "Integer times at which the particles' current steps began",
                         .messages = kStepped}),
  };
}();
// clang-format on

// Every member of a store is a vector with a row in its table (a member without one would be
// neither moved by a recut nor sent, saved or written).
static_assert(sizeof(GasParticles) == std::tuple_size_v<decltype(kGasFields)> * sizeof(std::vector<char>),
              "a member of GasParticles has no row in kGasFields");
static_assert(sizeof(CollisionlessParticles) ==
                  std::tuple_size_v<decltype(kCollisionlessFields)> * sizeof(std::vector<char>),
              "a member of CollisionlessParticles has no row in kCollisionlessFields");

template <class Store>
constexpr const auto& field_table() {
  static_assert(std::is_same_v<Store, GasParticles> || std::is_same_v<Store, CollisionlessParticles>);
  if constexpr (std::is_same_v<Store, GasParticles>) return kGasFields;
  else return kCollisionlessFields;
}

// Calls f(info, field) for every field of `store` (const or not), in table order.
template <class Store, class F>
void for_each_field_of(Store& store, F&& f) {
  std::apply([&](const auto&... row) { (f(row.info, store.*row.member), ...); },
             field_table<std::remove_const_t<Store>>());
}

// Calls f(field) for the fields of `store` that travel in `part` (one message::), in table order.
template <class Store, class F>
void for_each_field_in(Store& store, Messages part, F&& f) {
  for_each_field_of(store, [&](const FieldInfo& info, auto& values) {
    if ((info.messages & part) != 0) f(values);
  });
}

// Per particle, the bytes of the fields of `Store` that travel in `part`.
template <class Store>
constexpr std::size_t bytes_per_particle_in(Messages part) {
  return std::apply(
      [&](const auto&... row) {
        return ((((row.info.messages & part) != 0) ? sizeof(typename std::decay_t<decltype(row)>::Value) : 0) + ...);
      },
      field_table<Store>());
}

// ---- The stores' members that walk the table -------------------------------------------------

inline void GasParticles::resize(std::size_t n) {
  std::apply([&](const auto&... row) { ((this->*row.member).resize(n, row.initial), ...); }, kGasFields);
}

template <class F>
void GasParticles::for_each_field(F&& f) {
  for_each_field_of(*this, [&](const FieldInfo&, auto& values) { f(values); });
}

template <class F>
void GasParticles::for_each_derived_field(F&& f) {
  for_each_field_of(*this, [&](const FieldInfo& info, auto& values) {
    if (info.derived) f(values);
  });
}

inline void CollisionlessParticles::resize(std::size_t n) {
  std::apply([&](const auto&... row) { ((this->*row.member).resize(n, row.initial), ...); }, kCollisionlessFields);
}

template <class F>
void CollisionlessParticles::for_each_field(F&& f) {
  for_each_field_of(*this, [&](const FieldInfo&, auto& values) { f(values); });
}

}  // namespace fountain
