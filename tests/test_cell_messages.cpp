// What ranks send each other about a cell: packed and unpacked, every field comes back exactly, and nothing else is touched.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <vector>

#include "engine/CellMessages.hpp"
#include "hydro/MassTransfer.hpp"
#include "space/Space.hpp"

namespace fountain {
namespace {

// Fills every field of both stores with values that differ per particle and per seed.
template <class Store>
void scramble(Store& s, unsigned seed) {
  std::mt19937_64 rng(seed);
  s.for_each_field([&](auto& field) {
    for (auto& v : field) {
      // Random bytes, as a rank's state holds whatever the physics left there.
      unsigned char bytes[sizeof(v)];
      for (auto& b : bytes) b = static_cast<unsigned char>(rng());
      std::memcpy(&v, bytes, sizeof(v));
    }
  });
}

template <class Store>
bool same_particle(Store& a, Store& b, std::size_t i, const void* skip_a = nullptr) {
  bool same = true;
  std::vector<const void*> fields_b;
  b.for_each_field([&](auto& f) { fields_b.push_back(&f); });
  std::size_t k = 0;
  a.for_each_field([&](auto& f) {
    using V = std::decay_t<decltype(f)>;
    const V& g = *static_cast<const V*>(fields_b[k++]);
    if (static_cast<const void*>(&f) == skip_a) return;
    same = same && std::memcmp(&f[i], &g[i], sizeof(f[i])) == 0;
  });
  return same;
}

// Bitwise, as NaN bytes from scramble() must compare equal to themselves.
template <class T>
bool same_bytes(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

struct TwoRanks : ::testing::Test {
  GasParticles gas;
  CollisionlessParticles dm;
  Space space{SpaceConfig{}};
  void SetUp() override {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    gas.resize(600);
    dm.resize(300);
    for (auto& x : gas.x) x = {u(rng), u(rng), u(rng)};
    for (auto& x : dm.x) x = {u(rng), u(rng), u(rng)};
    for (std::size_t i = 0; i < gas.size(); ++i) gas.h[i] = 0.05, gas.id[i] = i;
    for (std::size_t i = 0; i < dm.size(); ++i) dm.id[i] = 1000 + i;
    SpaceConfig c;
    c.split_size = 64;
    space = Space(c);
    space.rebuild(gas, dm);
  }
  // A sender's state and a receiver's copy that differs from it everywhere, for both species.
  struct Sides {
    GasParticles sent_gas, got_gas;
    CollisionlessParticles sent_dm, got_dm;
  };
  Sides scrambled_sides(unsigned seed) const {
    Sides s{gas, gas, dm, dm};
    scramble(s.sent_gas, seed);
    scramble(s.sent_dm, seed + 1);
    scramble(s.got_gas, seed + 2);
    scramble(s.got_dm, seed + 3);
    return s;
  }
};

TEST_F(TwoRanks, CellStateCarriesTheFlaggedParticlesOnlyAndNeverTheWakeRequests) {
  const int c = space.leaves()[space.leaves().size() / 2];
  const Cell cell = space.cell(c);
  ASSERT_GT(cell.count, 2u);
  auto [sent_gas, got_gas, sent_dm, got_dm] = scrambled_sides(1);
  // Identity and the cell's ranges come from the shared recut, so they agree on both sides.
  sent_gas.id = got_gas.id = gas.id;
  std::vector<char> gas_moved(gas.size(), 0), dm_moved(dm.size(), 0);
  for (std::size_t i = cell.first; i < cell.first + cell.count; i += 2) gas_moved[i] = 1;
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; i += 3) dm_moved[i] = 1;
  const GasParticles before_gas = got_gas;
  const CollisionlessParticles before_dm = got_dm;

  std::vector<char> buffer;
  MessageWriter w(buffer);
  Space sender = space;
  sender.cell(c).h_max = 0.123;
  pack_cell_state(w, sender, sent_gas, sent_dm, c, gas_moved, dm_moved);
  MessageReader r(buffer);
  unpack_cell_state(r, space, got_gas, got_dm, c, gas_moved, dm_moved);
  EXPECT_TRUE(r.done()) << "the message holds more than the reader took";
  EXPECT_EQ(space.cell(c).h_max, 0.123) << "the cell record travels with it";

  GasParticles before_gas_copy = before_gas;
  CollisionlessParticles before_dm_copy = before_dm;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    if (gas_moved[i]) {
      EXPECT_TRUE(same_particle(got_gas, sent_gas, i, &got_gas.wake_bin)) << "gas particle " << i << " not carried";
      EXPECT_EQ(got_gas.wake_bin[i], before_gas.wake_bin[i]) << "wake request of " << i << " overwritten";
    } else {
      EXPECT_TRUE(same_particle(got_gas, before_gas_copy, i)) << "unflagged gas particle " << i << " changed";
    }
  }
  for (std::size_t i = 0; i < dm.size(); ++i) {
    if (dm_moved[i]) EXPECT_TRUE(same_particle(got_dm, sent_dm, i)) << "dark matter particle " << i << " not carried";
    else EXPECT_TRUE(same_particle(got_dm, before_dm_copy, i)) << "unflagged dark matter particle " << i << " changed";
  }
}

TEST_F(TwoRanks, StepChangedStateLeavesOutWhatEveryRankKeepsAlikeAndCarriesTheRest) {
  const int c = space.leaves()[space.leaves().size() / 3];
  const Cell cell = space.cell(c);
  ASSERT_GT(cell.count, 0u);
  ASSERT_GT(cell.dm_count, 0u);
  auto [sent_gas, got_gas, sent_dm, got_dm] = scrambled_sides(11);
  const GasParticles before_gas = got_gas;
  const CollisionlessParticles before_dm = got_dm;
  const std::vector<char> gas_all(gas.size(), 1), dm_all(dm.size(), 1);

  std::vector<char> whole, step;
  MessageWriter ww(whole), ws(step);
  pack_cell_state(ww, space, sent_gas, sent_dm, c, gas_all, dm_all, StateFields::All);
  pack_cell_state(ws, space, sent_gas, sent_dm, c, gas_all, dm_all, StateFields::StepChanged);
  const std::size_t left_out = cell.count * (sizeof(std::uint64_t) + sizeof(double) + sizeof(Vec3)) +
                               cell.dm_count * (sizeof(std::uint64_t) + sizeof(Species) + 2 * sizeof(double) +
                                                sizeof(std::uint64_t) + sizeof(Vec3));
  EXPECT_EQ(whole.size() - step.size(), left_out) << "exactly the fields kept alike are left out";
  MessageReader r(step);
  unpack_cell_state(r, space, got_gas, got_dm, c, gas_all, dm_all, StateFields::StepChanged);
  EXPECT_TRUE(r.done());

  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    EXPECT_TRUE(same_bytes(got_gas.id[i], before_gas.id[i]));
    EXPECT_TRUE(same_bytes(got_gas.mass_initial[i], before_gas.mass_initial[i]));
    EXPECT_TRUE(same_bytes(got_gas.x[i], before_gas.x[i])) << "positions are the receiver's own drift";
    EXPECT_TRUE(same_bytes(got_gas.wake_bin[i], before_gas.wake_bin[i]));
    // Everything else is the sender's: make the kept fields agree and compare whole particles.
    GasParticles a = got_gas;
    a.id[i] = sent_gas.id[i], a.mass_initial[i] = sent_gas.mass_initial[i], a.x[i] = sent_gas.x[i];
    EXPECT_TRUE(same_particle(a, sent_gas, i, &a.wake_bin)) << "gas particle " << i << " not carried";
  }
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) {
    EXPECT_TRUE(same_bytes(got_dm.x[i], before_dm.x[i]));
    EXPECT_TRUE(same_bytes(got_dm.mass[i], before_dm.mass[i]));
    EXPECT_TRUE(same_bytes(got_dm.v_full[i], sent_dm.v_full[i]));
    EXPECT_TRUE(same_bytes(got_dm.a_grav[i], sent_dm.a_grav[i]));
    EXPECT_TRUE(same_bytes(got_dm.time_bin[i], sent_dm.time_bin[i]));
    EXPECT_TRUE(same_bytes(got_dm.ti_begin[i], sent_dm.ti_begin[i]));
  }
}

TEST_F(TwoRanks, GhostResultsFitTheirAnnouncedSizeAndComeBackExactly) {
  const int c = space.leaves().front();
  GasParticles sent = gas, got = gas;
  scramble(sent, 5);
  std::vector<char> buffer;
  MessageWriter w(buffer);
  pack_ghost_results(w, space, sent, c);
  EXPECT_EQ(buffer.size(), ghost_results_bytes(space, c)) << "the receive is posted with this size";
  MessageReader r(buffer);
  unpack_ghost_results(r, space, got, c);
  const Cell& cell = space.cell(c);
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    EXPECT_EQ(std::memcmp(&got.rho[i], &sent.rho[i], sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(&got.p_over_rho_a[i], &sent.p_over_rho_a[i], sizeof(double)), 0);
    EXPECT_EQ(got.courant_bin[i], sent.courant_bin[i]);
    EXPECT_EQ(std::memcmp(&got.x[i], &gas.x[i], sizeof(Vec3)), 0) << "positions are not ghost results";
  }
}

TEST(HaloStepFields, EveryGasFieldIsEitherSentOrKnownNotToChangeInAHaloModeStep) {
  // Halo mode sends only the fields a step changes; the rest must be ones that a run without
  // feedback sites never changes but by the drift (positions) or not at all, or (the
  // potentials) that nothing reads of a held copy. With gravity the acceleration goes too,
  // which a holder's drift reads, and in periodic runs the mesh's part of it. A field added to GasParticles fails here until it
  // is placed in one list or another.
  GasParticles g;
  std::vector<const void*> sent, unchanged{&g.id, &g.mass_initial, &g.reservoir,
                                          &g.promoted, &g.promotion_time, &g.feedback_hot_energy, &g.x,
                                          &g.potential, &g.potential_mesh, &g.wake_bin};
  // The derived fields are changed by a step but worked out again by the holder's own drift.
  std::vector<const void*> derived;
  halo_step_fields(g, [&](auto& f) { sent.push_back(&f); });
  std::size_t gravity_fields = 0;
  halo_gravity_fields(g, [&](auto& f) {
    sent.push_back(&f);
    ++gravity_fields;
  });
  EXPECT_EQ(gravity_fields, 1u);
  // In periodic runs the mesh's acceleration too, which the predicted velocity reads.
  std::size_t mesh_fields = 0;
  halo_mesh_fields(g, [&](auto& f) {
    sent.push_back(&f);
    ++mesh_fields;
  });
  EXPECT_EQ(mesh_fields, 1u);
  // With star formation (no feedback sites) the masses conversion moves between gas and stars.
  std::size_t star_formation_fields = 0;
  halo_star_formation_fields(g, [&](auto& f) {
    sent.push_back(&f);
    ++star_formation_fields;
  });
  EXPECT_EQ(star_formation_fields, 2u);
  g.for_each_derived_field([&](auto& f) { derived.push_back(&f); });
  std::size_t fields = 0;
  g.for_each_field([&](auto& f) {
    ++fields;
    const int lists = (std::find(sent.begin(), sent.end(), &f) != sent.end() ? 1 : 0) +
                      (std::find(unchanged.begin(), unchanged.end(), &f) != unchanged.end() ? 1 : 0) +
                      (std::find(derived.begin(), derived.end(), &f) != derived.end() ? 1 : 0);
    EXPECT_EQ(lists, 1) << "gas field number " << fields << " must be in exactly one list";
  });
  EXPECT_EQ(sent.size() + unchanged.size() + derived.size(), fields);
  // A ghost message carries the derived fields of the ghost's results: the force loops of its
  // graph read them with no drift between.
  std::size_t ghost_derived = 0;
  ghost_fields(g, [&](auto& f) { ghost_derived += std::find(derived.begin(), derived.end(), &f) != derived.end(); });
  EXPECT_EQ(ghost_derived, 6u);
}

// A leaf's sender and receiver copies, differing everywhere, with every other particle of
// the leaf flagged as moved.
struct MovedGasCase {
  int c;
  GasParticles sent, got, before;
  std::vector<char> moved;
  std::size_t flagged = 0;
  MovedGasCase(const Space& space, const GasParticles& gas, unsigned seed)
      : c(space.leaves()[space.leaves().size() / 3]), sent(gas), got(gas), moved(gas.size(), 0) {
    scramble(sent, seed);
    scramble(got, seed + 1);
    before = got;
    const Cell& cell = space.cell(c);
    for (std::size_t i = cell.first; i < cell.first + cell.count; i += 2) moved[i] = 1, ++flagged;
  }
};

TEST_F(TwoRanks, MovedGasCarriesTheStepFieldsOfFlaggedParticlesOnly) {
  MovedGasCase m(space, gas, 6);
  const int c = m.c;
  ASSERT_GT(space.cell(c).count, 2u);
  GasParticles &sent = m.sent, &got = m.got;
  const GasParticles& before = m.before;
  const std::vector<char>& moved = m.moved;
  std::vector<char> buffer;
  MessageWriter w(buffer);
  pack_moved_gas(w, space, sent, c, moved);
  MessageReader r(buffer);
  unpack_moved_gas(r, space, got, c, moved);
  EXPECT_TRUE(r.done());
  for (std::size_t i = 0; i < gas.size(); ++i) {
    EXPECT_EQ(std::memcmp(&got.x[i], &before.x[i], sizeof(Vec3)), 0) << "positions are the drift's";
    EXPECT_EQ(got.id[i], before.id[i]);
    if (moved[i]) {
      EXPECT_EQ(std::memcmp(&got.v_full[i], &sent.v_full[i], sizeof(Vec3)), 0) << i;
      EXPECT_EQ(std::memcmp(&got.rho[i], &sent.rho[i], sizeof(double)), 0) << i;
      EXPECT_EQ(got.time_bin[i], sent.time_bin[i]) << i;
      EXPECT_EQ(got.limit_bin[i], sent.limit_bin[i]) << i;
    } else {
      EXPECT_EQ(std::memcmp(&got.v_full[i], &before.v_full[i], sizeof(Vec3)), 0) << i;
      EXPECT_EQ(got.time_bin[i], before.time_bin[i]) << i;
    }
  }
}

TEST_F(TwoRanks, MovedGasAfterTheGhostResultsLeavesThemToTheGhostMessage) {
  MovedGasCase m(space, gas, 15);
  const int c = m.c;
  const Cell& cell = space.cell(c);
  ASSERT_GT(cell.count, 2u);
  GasParticles &sent = m.sent, &got = m.got;
  const GasParticles& before = m.before;
  const std::vector<char>& moved = m.moved;
  const std::size_t flagged = m.flagged;
  std::vector<char> all, after_ghost;
  MessageWriter wa(all), wg(after_ghost);
  pack_moved_gas(wa, space, sent, c, moved);
  pack_moved_gas(wg, space, sent, c, moved, true);
  std::size_t ghost_bytes = 0;
  halo_ghost_fields(sent, [&](auto& f) { ghost_bytes += sizeof(f[0]); });
  EXPECT_EQ(all.size() - after_ghost.size(), flagged * ghost_bytes) << "only the ghost's results are left out";
  MessageReader r(after_ghost);
  unpack_moved_gas(r, space, got, c, moved, true);
  EXPECT_TRUE(r.done());
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!moved[i]) continue;
    EXPECT_TRUE(same_bytes(got.v_full[i], sent.v_full[i])) << i;
    EXPECT_TRUE(same_bytes(got.du_dt[i], sent.du_dt[i])) << i;
    EXPECT_TRUE(same_bytes(got.limit_bin[i], sent.limit_bin[i])) << i;
    EXPECT_TRUE(same_bytes(got.rho[i], before.rho[i])) << "rho came by the ghost message, not again: " << i;
    EXPECT_TRUE(same_bytes(got.balsara[i], before.balsara[i])) << i;
  }
}

TEST_F(TwoRanks, MovedGasOfALeafWithNoneFlaggedIsEmptyAndOfAWhollyFlaggedOneComesBackWhole) {
  MovedGasCase m(space, gas, 21);
  const Cell& cell = space.cell(m.c);
  std::vector<char> none(gas.size(), 0), every(gas.size(), 0);
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) every[i] = 1;
  std::vector<char> empty, whole, scattered;
  MessageWriter we(empty), ww(whole), ws(scattered);
  pack_moved_gas(we, space, m.sent, m.c, none);
  pack_moved_gas(ww, space, m.sent, m.c, every);
  pack_moved_gas(ws, space, m.sent, m.c, m.moved);
  EXPECT_TRUE(empty.empty());
  EXPECT_EQ(whole.size() * m.flagged, scattered.size() * cell.count) << "the same bytes per particle either way";
  MessageReader r(whole);
  unpack_moved_gas(r, space, m.got, m.c, every);
  EXPECT_TRUE(r.done());
  for (std::size_t i = 0; i < gas.size(); ++i) {
    const bool inside = i >= cell.first && i < cell.first + cell.count;
    const GasParticles& expect = inside ? m.sent : m.before;
    EXPECT_TRUE(same_bytes(m.got.v_full[i], expect.v_full[i])) << i;
    EXPECT_TRUE(same_bytes(m.got.rho[i], expect.rho[i])) << i;
    EXPECT_TRUE(same_bytes(m.got.ti_begin[i], expect.ti_begin[i])) << i;
  }
}

TEST_F(TwoRanks, ScatteredParticlesComeBackWhole) {
  GasParticles sent = gas, got = gas;
  scramble(sent, 8);
  scramble(got, 9);
  const GasParticles before = got;
  const std::vector<std::size_t> picks{5, 2, 400, 77};
  std::vector<char> buffer;
  MessageWriter w(buffer);
  pack_particles(w, sent, picks);
  MessageReader r(buffer);
  unpack_particles(r, got, picks);
  EXPECT_TRUE(r.done());
  GasParticles before_copy = before;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    const bool picked = std::find(picks.begin(), picks.end(), i) != picks.end();
    if (picked) EXPECT_TRUE(same_particle(got, sent, i)) << i;
    else EXPECT_TRUE(same_particle(got, before_copy, i)) << i;
  }
}

TEST_F(TwoRanks, ReaderRefusesAShortMessage) {
  std::vector<char> buffer(3);
  MessageReader r(buffer);
  EXPECT_THROW((void)r.get<double>(), std::logic_error);
}


// A permutation that leaves most of the store in place (as a rebuild's mostly does) moves
// exactly the particles it names: pieces it does not touch are skipped, pieces it touches
// are gathered whole, and a shorter order drops the tail.
TEST(GasParticlesPermute, MovesWhatTheOrderMovesAndKeepsTheRest) {
  constexpr std::size_t n = 20000;
  auto store = [] {
    GasParticles g;
    g.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      g.id[i] = 1000 + i;
      g.x[i] = {static_cast<double>(i), 0.5 * static_cast<double>(i), 1.0};
      g.u[i] = 3.0 * static_cast<double>(i);
      g.time_bin[i] = static_cast<TimeBin>(i % 50);
      g.mass[i] = 2.5;  // all alike: left as it is
    }
    g.reservoir[15500] = 7.0;  // alike but for one particle, which the rotation moves
    return g;
  };
  std::vector<std::size_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = k;
  std::swap(order[9000], order[9001]);                                        // inside one piece
  std::rotate(order.begin() + 15000, order.begin() + 15001, order.begin() + 17000);  // a shift across pieces
  for (const std::size_t keep : {n, n - 100}) {
    GasParticles g = store();
    std::vector<std::size_t> o(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep));
    g.permute(o);
    ASSERT_EQ(g.size(), keep);
    for (std::size_t k = 0; k < keep; ++k) {
      const std::size_t was = o[k];
      ASSERT_EQ(g.id[k], 1000 + was) << "slot " << k;
      ASSERT_EQ(g.x[k].x, static_cast<double>(was));
      ASSERT_EQ(g.u[k], 3.0 * static_cast<double>(was));
      ASSERT_EQ(g.time_bin[k], static_cast<TimeBin>(was % 50));
      ASSERT_EQ(g.mass[k], 2.5);
      ASSERT_EQ(g.reservoir[k], was == 15500 ? 7.0 : 0.0) << "slot " << k;
    }
    g.for_each_field([&](auto& f) { EXPECT_EQ(f.size(), keep) << "every field, alike or not, takes the new length"; });
  }
  // A recut's permute leaves the derived fields in place, unless the number of particles changes.
  for (const std::size_t keep : {n, n - 100}) {
    GasParticles g = store();
    for (std::size_t i = 0; i < n; ++i) g.soundspeed[i] = g.rho_msph[i] = static_cast<double>(i);
    std::vector<std::size_t> o(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep));
    g.permute(o, {}, nullptr, GasParticles::Derived::Stay);
    for (std::size_t k = 0; k < keep; ++k) {
      ASSERT_EQ(g.u[k], 3.0 * static_cast<double>(o[k])) << "slot " << k;
      const double derived = static_cast<double>(keep == n ? k : o[k]);
      ASSERT_EQ(g.soundspeed[k], derived) << "slot " << k << " of " << keep;
      ASSERT_EQ(g.rho_msph[k], derived) << "slot " << k << " of " << keep;
    }
  }
}

// Spawning and dissolving in halo mode send the other holders only the star_formation_event
// fields of the particles they touch: a dissolved particle's share taken in (heated, and
// cooled by colder gas) and a parent's hidden stars given up must change nothing else.
TEST(StarFormationEventFields, AbsorbingADissolvedParticleChangesOnlyTheEventFields) {
  GasParticles g;
  g.resize(3);
  scramble(g, 11);
  // Sane values where absorb computes: positive masses and energies, finite velocities.
  for (std::size_t i = 0; i < 3; ++i) {
    g.mass[i] = 1.0 + static_cast<double>(i);
    g.mass_stars_hidden[i] = 0.25;
    g.u[i] = g.u_full[i] = 100.0 * static_cast<double>(i + 1);
    g.du_dt[i] = g.du_dt_cool[i] = -3.0;
    g.v[i] = g.v_full[i] = Vec3{1.0, -2.0, 0.5} * static_cast<double>(i + 1);
  }
  std::vector<const void*> event;
  for_each_field_in(g, message::star_formation_event, [&](auto& f) { event.push_back(&f); });
  EXPECT_EQ(event.size(), 9u);
  auto image = [&](const GasParticles& s) {
    std::vector<std::vector<char>> out;
    const_cast<GasParticles&>(s).for_each_field([&](auto& f) {
      const bool sent = std::find(event.begin(), event.end(), static_cast<const void*>(&f)) != event.end();
      const auto* bytes = reinterpret_cast<const char*>(f.data());
      out.emplace_back(sent ? std::vector<char>{} : std::vector<char>(bytes, bytes + f.size() * sizeof(f[0])));
    });
    return out;
  };
  const auto before = image(g);
  hydro::absorb(g, 1, 0.5, 0.1, Vec3{0.0, 1.0, 0.0}, 1000.0, 2.0);  // heated
  hydro::absorb(g, 2, 0.5, 0.1, Vec3{0.0, 1.0, 0.0}, 1.0, 0.0);     // cooled by mixing
  EXPECT_NE(g.u[1], 200.0);
  EXPECT_LT(g.u[2], 300.0);
  // The dissolved particle itself, and a parent that spawned.
  g.mass[0] = g.mass_stars_hidden[0] = g.reservoir[0] = 0.0;
  g.mass_stars_hidden[1] = 0.0;
  const auto after = image(g);
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t k = 0; k < before.size(); ++k) EXPECT_EQ(after[k], before[k]) << "gas field number " << k + 1;
}

}  // namespace
}  // namespace fountain
