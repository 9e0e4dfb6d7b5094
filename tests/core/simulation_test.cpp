// The fixed-step simulation: contact before cut, no drop-outs, convergence of
// the moving contact signal, determinism, validation.
#include "terracut/core/simulation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "terracut/core/error.hpp"
#include "test_terrains.hpp"

namespace terracut {
namespace {

constexpr double kRadius = 0.4, kHeight = 0.2, kCutY = 0.1;

// The paper's experiment 1: a horizontal cut at half the dome's height moving
// along +Z through the dome in 2 s at 1 kHz.
Motion experiment1_motion() {
  Motion m;
  m.name = "horizontal";
  m.keyframes = {{0.0, {{0.5, kCutY, -0.1}, Quat{}}}, {2.0, {{0.5, kCutY, 1.1}, Quat{}}}};
  return m;
}

struct Signal {
  std::vector<double> measured, exact;
  double cell = 0.0;
};

Signal run_dome_cut(int n, Representation rep) {
  SimParams p;
  p.grid = test::square_spec(n, n, 1.0, kHeight);
  p.representation = rep;
  p.blade.length_m = 1.2;
  Simulation sim(p, test::dome(p.grid, 0.5, 0.5, kRadius, kHeight));
  Motion m = experiment1_motion();
  Signal out;
  out.cell = p.grid.cell_z_m();
  for (int i = 0; i <= 2000; ++i) {
    BladePose pose = m.sample(i / 1000.0);
    const StepOutput& o = sim.step(pose);
    out.measured.push_back(o.contact.length_m);
    out.exact.push_back(test::dome_chord(kCutY, pose.position_m.z, 0.5, kRadius, kHeight));
  }
  return out;
}

// Blade travel per step in experiment 1 (1.2 m in 2000 steps), metres.
constexpr double kTravelPerStep = 1.2 / 2000.0;

// First and last step with a non-zero value, or {-1, -1}.
std::pair<int, int> episode(const std::vector<double>& v) {
  int first = -1, last = -1;
  for (int i = 0; i < int(v.size()); ++i) {
    if (v[size_t(i)] > 0.0) {
      if (first < 0) first = i;
      last = i;
    }
  }
  return {first, last};
}

// With the surface representation, a blade moving steadily through material
// never loses contact between samples, from 50x50 up: the contact is one
// unbroken episode, which starts and ends within a cell of blade travel of
// the exact one (the last row of samples ahead of the blade decides the end).
TEST(Simulation, SurfaceHasNoDropOuts) {
  for (int n : {50, 100, 200, 400}) {
    Signal s = run_dome_cut(n, Representation::kSurface);
    auto [first, last] = episode(s.measured);
    auto [exact_first, exact_last] = episode(s.exact);
    ASSERT_GE(first, 0);
    int gaps = 0;
    for (int i = first; i <= last; ++i) gaps += s.measured[size_t(i)] <= 0.0;
    EXPECT_EQ(gaps, 0) << "n=" << n;
    double cell_steps = s.cell / kTravelPerStep;
    EXPECT_LE(std::abs(first - exact_first), cell_steps + 1) << "n=" << n;
    EXPECT_LE(std::abs(last - exact_last), cell_steps + 1) << "n=" << n;
  }
}

// Columns count a blade resting on a column's top as touching it (closed
// boxes, as the slab method tests them): a horizontal blade moving through a
// row of cells stays in contact with the columns it has cut to its height,
// so the signal has no gaps and is a staircase that steps only when the blade
// enters the next row of cells (the paper's "minimum step size of the
// contact length"), converging to the exact chord as the cells shrink.
TEST(Simulation, ColumnsGiveAStaircaseWithoutGaps) {
  double previous = INFINITY;
  for (int n : {25, 50, 100, 200}) {
    Signal s = run_dome_cut(n, Representation::kColumns);
    auto [first, last] = episode(s.measured);
    ASSERT_GE(first, 0);
    int gaps = 0, steps_inside_rows = 0, changes_inside_rows = 0;
    for (int i = first; i <= last; ++i) gaps += s.measured[size_t(i)] <= 0.0;
    EXPECT_EQ(gaps, 0) << "n=" << n;
    // Within a row of cells the contact does not change.
    for (int i = first + 1; i <= last; ++i) {
      double z0 = -0.1 + kTravelPerStep * (i - 1), z1 = -0.1 + kTravelPerStep * i;
      // Skip the steps that cross or land on a row boundary (where rounding
      // of the pose decides the row).
      auto near_boundary = [&](double z) { return std::abs(z / s.cell - std::round(z / s.cell)) < 1e-6; };
      if (std::floor(z0 / s.cell) != std::floor(z1 / s.cell) || near_boundary(z0) || near_boundary(z1)) continue;
      ++steps_inside_rows;
      changes_inside_rows += s.measured[size_t(i)] != s.measured[size_t(i - 1)];
    }
    EXPECT_GT(steps_inside_rows, 0);
    EXPECT_EQ(changes_inside_rows, 0) << "n=" << n;
    double sum_sq = 0.0;
    for (size_t i = 0; i < s.exact.size(); ++i) sum_sq += std::pow(s.measured[i] - s.exact[i], 2);
    double rms = std::sqrt(sum_sq / s.exact.size());
    EXPECT_LT(rms, 0.8 * previous) << "n=" << n;
    previous = rms;
  }
}

// The moving contact signal converges to the exact chord as resolution grows.
TEST(Simulation, MovingContactConvergesToExactChord) {
  double previous = INFINITY;
  for (int n : {25, 50, 100, 200, 400}) {
    Signal s = run_dome_cut(n, Representation::kSurface);
    double sum_sq = 0.0;
    for (size_t i = 0; i < s.exact.size(); ++i) sum_sq += std::pow(s.measured[i] - s.exact[i], 2);
    double rms = std::sqrt(sum_sq / s.exact.size());
    // The blade sees the surface up to a cell ahead of it: the error is within
    // a few cells' worth of chord change and shrinks with the cell size.
    EXPECT_LT(rms, 3.0 * s.cell) << "n=" << n;
    EXPECT_LT(rms, 0.8 * previous) << "n=" << n;
    previous = rms;
  }
}

// Contact is measured before the step's cut: a blade put down inside a slab
// reports its contact on the step that cuts.
TEST(Simulation, SmallStepsCutEveryRowTheyCross) {
  // A blade moving 0.05 cell per step along -Z over a grid whose origin is
  // not at zero: its positions fall within rounding of sample centres, which
  // each sweep's rasteriser may decide either way. Consecutive sweeps
  // overlap, so no row is missed (before, 6 of 10 rows were never cut).
  for (const double origin : {-1.0, 0.0, 0.37}) {
    SimParams p;
    p.grid = grid_of_cells(200, 200, 0.01, {origin, 0.0, origin});
    p.blade.length_m = 0.4;
    for (Representation rep : {Representation::kSurface, Representation::kColumns}) {
      p.representation = rep;
      Simulation sim(p, std::vector<float>(200 * 200, 0.3f));
      const double z0 = origin + 1.275, x = origin + 1.0;
      for (int i = 0; i <= 200; ++i) sim.step({{x, 0.25, z0 - 0.0005 * i}, Quat{}});
      // Every sample row whose centre the blade passed, 0.2 cm past the
      // start to 0.2 cm before the end, is at the blade's height.
      for (int r = 0; r < 200; ++r) {
        const double zc = origin + (r + 0.5) * 0.01;
        if (zc > z0 - 0.002 || zc < z0 - 0.1 + 0.002) continue;
        EXPECT_NEAR(sim.grid().height(100, r), 0.25, 1e-6)
            << "row " << r << ", origin " << origin << ", " << to_string(rep);
      }
    }
  }
}

// The lattice tests: a 2 m blade over 60 x 60 cells of 2 cm covered 0.3 m
// deep, its line through the centre of cell (30, 30) along a lattice
// direction (lc, lr) in cells, so that it runs exactly through a centre
// every few cells.
constexpr int kLatticeCells = 60;
constexpr double kLatticeCell = 0.02;
constexpr std::pair<int, int> kLattice[] = {{1, 0}, {0, 1}, {1, 1}, {2, 1}, {3, 1}, {3, -1}, {1, -2}};

Simulation lattice_simulation(double origin, Representation rep) {
  SimParams p;
  p.grid = grid_of_cells(kLatticeCells, kLatticeCells, kLatticeCell, {origin, 0.0, origin});
  p.blade.length_m = 2.0;
  p.representation = rep;
  return Simulation(p, std::vector<float>(kLatticeCells * kLatticeCells, 0.3f));
}

/// Calls f(c, r, m) for the cells (30 + m lc, 30 + m lr) on the grid.
template <class F>
void for_lattice_line(int lc, int lr, F&& f) {
  for (int m = -kLatticeCells; m <= kLatticeCells; ++m) {
    const int c = 30 + m * lc, r = 30 + m * lr;
    if (c >= 0 && r >= 0 && c < kLatticeCells && r < kLatticeCells) f(c, r, m);
  }
}

TEST(Simulation, TurningStepsCutEverySampleTheyCross) {
  // A 2 m blade pushing while it turns about the vertical fast enough that
  // one end goes back across its line while the other goes forward: the
  // edge turns about a point on it. At step kAt its line runs along a
  // lattice direction exactly through a row of sample centres, so those
  // centres lie, to rounding, on the line two consecutive sweeps share.
  // Every one of them the edge then passed is cut to its height, at every
  // lattice direction, turning either way, in both representations and
  // wherever the terrain lies. (The sweeps once reached back along each
  // end's own motion: between the edge's middle and the point that stood
  // still the reach pointed forward, and a row of such centres was never
  // cut: in the soil, a pile standing on them slid into the trench behind
  // the blade.)
  constexpr int kAt = 40;
  constexpr double kBladeY = 0.25, kPush = 3e-4, kTurn = 5e-4;  // m and rad a step
  for (const double origin : {0.0, 0.37, 1e5}) {
    for (Representation rep : {Representation::kSurface, Representation::kColumns}) {
      for (const auto& direction : kLattice) {
        // (Not a structured binding: clang 14 cannot capture one in a lambda.)
        const int lc = direction.first, lr = direction.second;
        for (const double spin : {1.0, -1.0}) {
          Simulation sim = lattice_simulation(origin, rep);
          const double cx = origin + 30.5 * kLatticeCell, cz = cx;
          const double yaw_at = -std::atan2(double(lr), double(lc));  // local +X -> (cos yaw, -sin yaw)
          const double nx = std::sin(yaw_at), nz = std::cos(yaw_at);  // the edge's normal, its push
          for (int i = 0; i <= 2 * kAt; ++i) {
            const double k = i - kAt;
            sim.step({{cx + nx * kPush * k, kBladeY, cz + nz * kPush * k},
                      quat_from_axis_angle({0.0, 1.0, 0.0}, yaw_at + spin * kTurn * k)});
          }
          // The point of the edge that stands still, kPush / kTurn from the
          // middle (a point `along` from it moves kPush - along * spin *
          // kTurn along the normal): the centres within two cells of it are
          // left out (their motion is within rounding's reach).
          const double still = spin * kPush / kTurn;
          int checked = 0;
          for_lattice_line(lc, lr, [&](int c, int r, int m) {
            const double along = m * std::hypot(double(lc), double(lr)) * kLatticeCell;  // toward +X at yaw_at
            if (std::abs(along - still) < 2.0 * kLatticeCell) return;
            ++checked;
            EXPECT_NEAR(sim.grid().height(c, r), kBladeY, 1e-6)
                << "cell (" << c << ", " << r << ") on the line along (" << lc << ", " << lr << "), turn " << spin
                << ", origin " << origin << ", " << to_string(rep);
          });
          EXPECT_GE(checked, 10);
        }
      }
    }
  }
}

TEST(Simulation, ABladeSetDownCutsEveryCentreOnItsLine) {
  // A blade set down (its first step, no motion) with its line along a
  // lattice direction exactly through a row of sample centres, then lowered
  // straight down in a second step: each centre on the line is under its
  // edge and is cut to the edge's height both times, wherever the terrain
  // lies. (A sweep with no motion across the line is a line in plan, on
  // which the rasterisers decide a centre either way; the step now also
  // cuts a band a millionth of a cell either side of the edge. Without it,
  // centres on the line were left standing under the edge, which ones
  // depending on the terrain's place, and a blade that then backed a
  // little pushed their soil behind its line.)
  for (const double origin : {0.0, 0.37, 1000.0, 1e5, 1e6}) {
    for (Representation rep : {Representation::kSurface, Representation::kColumns}) {
      for (const auto& direction : kLattice) {
        // (Not a structured binding: clang 14 cannot capture one in a lambda.)
        const int lc = direction.first, lr = direction.second;
        Simulation sim = lattice_simulation(origin, rep);
        const double cx = origin + 30.5 * kLatticeCell, cz = cx;
        const Quat yaw = quat_from_axis_angle({0.0, 1.0, 0.0}, -std::atan2(double(lr), double(lc)));
        for (const double y : {0.25, 0.2}) {
          sim.step({{cx, y, cz}, yaw});
          for_lattice_line(lc, lr, [&](int c, int r, int) {
            EXPECT_NEAR(sim.grid().height(c, r), y, 1e-6)
                << "cell (" << c << ", " << r << ") on the line along (" << lc << ", " << lr << "), edge at " << y
                << ", origin " << origin << ", " << to_string(rep);
          });
        }
      }
    }
  }
}

TEST(Simulation, ContactIsMeasuredBeforeTheCut) {
  for (Representation rep : {Representation::kColumns, Representation::kSurface}) {
    SimParams p;
    p.grid = test::square_spec(20, 20);
    p.representation = rep;
    p.blade.length_m = 0.5;
    Simulation sim(p, std::vector<float>(400, 0.5f));
    sim.step({{0.5, 0.2, 0.31}, Quat{}});
    const StepOutput& o = sim.step({{0.5, 0.2, 0.42}, Quat{}});
    EXPECT_NEAR(o.contact.length_m, 0.5, 1e-9) << to_string(rep);
    EXPECT_GT(o.cut.removed_volume_m3, 0.0) << to_string(rep);
    EXPECT_FALSE(o.cut.changed.empty());
    EXPECT_EQ(o.step, 1);
    EXPECT_DOUBLE_EQ(o.t_s, 0.001);
    EXPECT_GE(o.timers.total_s, o.timers.contact_s);
  }
}

// The same inputs give the same state, bitwise.
TEST(Simulation, Deterministic) {
  for (Representation rep : {Representation::kColumns, Representation::kSurface}) {
    std::uint64_t hashes[2];
    std::vector<double> contacts[2];
    for (int run = 0; run < 2; ++run) {
      SimParams p;
      p.grid = test::square_spec(64, 64, 1.0, kHeight);
      p.representation = rep;
      p.blade.length_m = 0.7;
      Simulation sim(p, test::dome(p.grid, 0.5, 0.5, kRadius, kHeight));
      std::mt19937 rng(99);
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      for (int i = 0; i < 500; ++i) {
        double a = 6.28 * i / 500.0;
        Vec3 euler{20.0 * unit(rng), 360.0 * unit(rng), 30.0 * (unit(rng) - 0.5)};
        sim.step({{0.5 + 0.3 * std::cos(a), 0.05 + 0.1 * unit(rng), 0.5 + 0.3 * std::sin(a)},
                  quat_from_euler_deg(euler)});
        contacts[run].push_back(sim.last().contact.length_m);
      }
      hashes[run] = sim.grid().state_hash();
    }
    EXPECT_EQ(hashes[0], hashes[1]);
    EXPECT_EQ(contacts[0], contacts[1]);
  }
}

// A non-finite pose is ignored: nothing is measured or cut, and the state stays valid.
TEST(Simulation, NonFinitePoseIsHarmless) {
  SimParams p;
  p.grid = test::square_spec(10, 10);
  Simulation sim(p, std::vector<float>(100, 0.5f));
  sim.step({{0.5, 0.2, 0.5}, Quat{}});
  const StepOutput& o = sim.step({{NAN, 0.2, 0.5}, Quat{}});
  EXPECT_EQ(o.contact.length_m, 0.0);
  EXPECT_EQ(o.cut.removed_volume_m3, 0.0);
  EXPECT_TRUE(std::isfinite(o.pose.position_m.x));
  EXPECT_EQ(sim.grid().conservation_error_m(), 0.0);
}

TEST(Simulation, ResetRestoresTheTerrain) {
  SimParams p;
  p.grid = test::square_spec(10, 10);
  Simulation sim(p, std::vector<float>(100, 0.5f));
  std::uint64_t start = sim.grid().state_hash();
  sim.step({{0.5, 0.2, 0.1}, Quat{}});
  sim.step({{0.5, 0.2, 0.9}, Quat{}});
  EXPECT_NE(sim.grid().state_hash(), start);
  sim.reset();
  EXPECT_EQ(sim.grid().state_hash(), start);
  EXPECT_EQ(sim.step_count(), 0);
}

// Bad parameters are refused at construction with a message naming the field.
TEST(Simulation, InvalidParametersNameTheField) {
  auto message = [](SimParams p, std::vector<float> h) -> std::string {
    try {
      Simulation sim(p, std::move(h));
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  SimParams good;
  good.grid = test::square_spec(4, 4);
  std::vector<float> h(16, 0.1f);
  SimParams p = good;
  p.grid.cols = 0;
  EXPECT_NE(message(p, {}).find("grid.cols"), std::string::npos);
  p = good;
  p.grid.rows = kMaxGridSide + 1;
  EXPECT_NE(message(p, h).find("grid.rows"), std::string::npos);
  p = good;
  p.grid.size_x_m = NAN;
  EXPECT_NE(message(p, h).find("grid.size_x_m"), std::string::npos);
  p = good;
  p.grid.size_z_m = -1.0;
  EXPECT_NE(message(p, h).find("grid.size_z_m"), std::string::npos);
  p = good;
  p.rate_hz = 0.0;
  EXPECT_NE(message(p, h).find("rate_hz"), std::string::npos);
  p = good;
  p.blade.length_m = INFINITY;
  EXPECT_NE(message(p, h).find("blade.length_m"), std::string::npos);
  p = good;
  EXPECT_NE(message(p, std::vector<float>(15, 0.1f)).find("expected cols x rows"), std::string::npos);
  std::vector<float> bad = h;
  bad[5] = NAN;
  EXPECT_NE(message(p, bad).find("(col 1, row 1)"), std::string::npos);
  bad[5] = -0.5f;
  EXPECT_NE(message(p, bad).find("(col 1, row 1)"), std::string::npos);
  EXPECT_EQ(message(good, h), "");
}

TEST(Motion, InterpolatesPositionLinearlyAndRotationBySlerp) {
  Motion m;
  m.keyframes = {{0.0, {{0, 0, 0}, Quat{}}}, {2.0, {{2, 4, -2}, quat_from_euler_deg({0, 0, 90})}}};
  BladePose mid = m.sample(1.0);
  EXPECT_NEAR(mid.position_m.x, 1.0, 1e-12);
  EXPECT_NEAR(mid.position_m.y, 2.0, 1e-12);
  EXPECT_NEAR(mid.position_m.z, -1.0, 1e-12);
  EXPECT_NEAR(euler_deg_from_quat(mid.orientation).z, 45.0, 1e-9);
  EXPECT_NEAR(m.sample(-1.0).position_m.x, 0.0, 0.0);
  EXPECT_NEAR(m.sample(5.0).position_m.x, 2.0, 0.0);
  // +45 degrees about Z raises the blade's +X end.
  Segment e = blade_segment({2.0}, {{0, 0, 0}, quat_from_euler_deg({0, 0, 45})});
  EXPECT_NEAR(e.b.y, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(e.b.x, std::sqrt(0.5), 1e-12);
  Motion bad = m;
  bad.keyframes[1].t_s = 0.0;
  EXPECT_NE(validate(bad).find("keyframe 1"), std::string::npos);
  EXPECT_EQ(validate(m), "");
}

// A listener that records what it hears of edits.
struct EditRecorder final : StepListener {
  std::vector<Rect> edits;
  Vec3 on_step(const StepOutput&) noexcept override { return {}; }
  void on_edit(const Rect& changed) noexcept override { edits.push_back(changed); }
};

// An edit between steps writes exactly its rectangle, keeps height + removed =
// initial, reports the rectangle to the caller and to every listener, and is
// seen by the next step's contact.
TEST(Simulation, EditHeightsWritesItsRectangleAndTellsTheListeners) {
  SimParams p;
  p.grid = test::square_spec(10, 10);
  p.representation = Representation::kColumns;
  p.blade.length_m = 2.0;
  Simulation sim(p, std::vector<float>(100, 0.5f));
  EditRecorder recorder;
  sim.add_listener(recorder);
  const Rect rect{2, 3, 5, 4};  // cols 2..4 of row 3
  const std::vector<float> values{0.1f, 0.2f, 0.3f};
  EXPECT_EQ(sim.edit_heights(rect, values), rect);
  ASSERT_EQ(recorder.edits.size(), 1u);
  EXPECT_EQ(recorder.edits[0], rect);
  for (int r = 0; r < 10; ++r) {
    for (int c = 0; c < 10; ++c) {
      const bool inside = r == 3 && c >= 2 && c < 5;
      const float expected = inside ? values[size_t(c - 2)] : 0.5f;
      EXPECT_EQ(sim.grid().height(c, r), expected) << c << "," << r;
      const std::int64_t i = sim.grid().index(c, r);
      EXPECT_EQ(sim.grid().heights()[i] + sim.grid().removed_at(i), sim.grid().initial()[i]);
    }
  }
  EXPECT_LE(sim.grid().conservation_error_m(), 1e-7);
  // A blade along X at y = 0.25 through row 3 (z = 0.35) is inside the
  // columns taller than that: the 7 untouched ones (0.5 m) and the 0.3 m
  // one, 8 cells of 0.1 m (the blade spans the grid).
  const StepOutput& out = sim.step({{0.5, 0.25, 0.35}, Quat{}});
  EXPECT_NEAR(out.contact.length_m, 0.8, 1e-9);
}

// Reset restores the terrain and tells every listener that the whole grid
// changed (whoever caches heights refreshes them), as an edit does.
TEST(Simulation, ResetTellsTheListenersTheWholeGridChanged) {
  SimParams p;
  p.grid = test::square_spec(6, 4);
  Simulation sim(p, std::vector<float>(24, 0.5f));
  EditRecorder recorder;
  sim.add_listener(recorder);
  sim.step({{0.5, 0.2, 0.1}, Quat{}});
  EXPECT_TRUE(recorder.edits.empty());  // a step is no edit
  sim.reset();
  ASSERT_EQ(recorder.edits.size(), 1u);
  EXPECT_EQ(recorder.edits[0], (Rect{0, 0, 6, 4}));
}

// The simulation owns the heights: grid() is read-only, and a listener
// changes heights only through lower_sample and move_height, from inside
// its own callbacks.
static_assert(std::is_same_v<decltype(std::declval<Simulation&>().grid()), const HeightGrid&>,
              "the terrain is changed through the simulation, not through grid()");

struct SoilPusher final : StepListener {
  Simulation* sim = nullptr;
  std::int64_t from = 0, to = 0;
  float amount_m = 0.0f, lower_to_m = 0.0f;
  std::int64_t lowered = -1;
  Vec3 on_step(const StepOutput&) noexcept override {
    sim->move_height(from, to, amount_m);
    if (lowered >= 0) sim->lower_sample(lowered, lower_to_m);
    sim->include_changed({0, 0, 3, 1});
    return {};
  }
  void on_edit(const Rect&) noexcept override {
    if (lowered >= 0) sim->lower_sample(lowered, lower_to_m);  // e.g. a height bound
  }
};

TEST(Simulation, AListenerChangesHeightsThroughTheSimulation) {
  SimParams p;
  p.grid = test::square_spec(4, 4);
  p.blade.length_m = 0.1;
  Simulation sim(p, std::vector<float>(16, 0.5f));
  SoilPusher pusher;
  pusher.sim = &sim;
  pusher.from = sim.grid().index(0, 0);
  pusher.to = sim.grid().index(1, 0);
  pusher.amount_m = 0.125f;
  pusher.lowered = sim.grid().index(2, 0);
  pusher.lower_to_m = 0.25f;
  sim.add_listener(pusher);
  const double volume = sim.grid().volume_m3();
  // A step far above the soil cuts nothing: only the listener changes heights.
  const StepOutput& out = sim.step({{0.5, 2.0, 0.5}, Quat{}});
  EXPECT_EQ(sim.grid().height(0, 0), 0.375f);
  EXPECT_EQ(sim.grid().height(1, 0), 0.625f);
  EXPECT_EQ(sim.grid().height(2, 0), 0.25f);
  EXPECT_EQ(out.changed, (Rect{0, 0, 3, 1}));  // what the listener reported
  // The move keeps the volume; the lowering removes a quarter of a cell's column.
  EXPECT_NEAR(sim.grid().volume_m3(), volume - 0.25 * sim.grid().spec().cell_area_m2(), 1e-9);
  // lower_sample never raises a sample, and never goes below the floor.
  pusher.amount_m = 0.0f;
  pusher.lower_to_m = 0.4f;
  sim.step({{0.5, 2.0, 0.5}, Quat{}});
  EXPECT_EQ(sim.grid().height(2, 0), 0.25f);
  pusher.lower_to_m = -1.0f;
  sim.step({{0.5, 2.0, 0.5}, Quat{}});
  EXPECT_EQ(sim.grid().height(2, 0), 0.0f);
  // Outside a listener's callbacks the simulation refuses.
  EXPECT_THROW(sim.move_height(pusher.from, pusher.to, 0.1f), std::logic_error);
  EXPECT_THROW(sim.lower_sample(pusher.lowered, 0.1f), std::logic_error);
  // From on_edit (an edit, a reset) it may: the reset's notification lowers it again.
  pusher.lower_to_m = 0.125f;
  sim.reset();
  EXPECT_EQ(sim.grid().height(2, 0), 0.125f);
  EXPECT_EQ(sim.grid().height(0, 0), 0.5f);
}

// Bad edits are refused with a message naming what was wrong, and nothing is
// written.
TEST(Simulation, EditHeightsRefusesBadInputAndWritesNothing) {
  SimParams p;
  p.grid = test::square_spec(4, 4);
  Simulation sim(p, std::vector<float>(16, 0.5f));
  const std::uint64_t start = sim.grid().state_hash();
  auto message = [&](Rect rect, std::vector<float> v) -> std::string {
    try {
      sim.edit_heights(rect, v);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message({0, 0, 5, 1}, std::vector<float>(5, 0.1f)).find("inside the 4 x 4 grid"),
            std::string::npos);
  EXPECT_NE(message({-1, 0, 1, 1}, std::vector<float>(2, 0.1f)).find("inside"), std::string::npos);
  EXPECT_NE(message({1, 1, 1, 2}, {}).find("non-empty"), std::string::npos);
  EXPECT_NE(message({0, 0, 2, 2}, std::vector<float>(3, 0.1f)).find("expected 2 x 2 values"),
            std::string::npos);
  EXPECT_NE(message({0, 0, 2, 2}, {0.1f, 0.1f, NAN, 0.1f}).find("(col 0, row 1)"),
            std::string::npos);
  EXPECT_NE(message({1, 2, 3, 3}, {0.1f, -0.2f}).find("(col 2, row 2)"), std::string::npos);
  EXPECT_EQ(sim.grid().state_hash(), start);
}

// With flowing soil, a spike made by an edit slides down to the angle of
// repose in the following steps (the blade held far above the terrain), and
// no volume is lost.
TEST(Simulation, EditHeightsWakesTheSoilFlow) {
  SimParams p;
  p.grid = test::square_spec(21, 21);  // cells of 1/21 m
  p.soil.model = SoilModel::kFlow;
  p.soil.material.repose_deg = 34.0;
  Simulation sim(p, std::vector<float>(21 * 21, 0.0f));
  const float spike = 0.2f;
  sim.edit_heights({10, 10, 11, 11}, std::vector<float>{spike});
  const double volume = sim.grid().volume_m3();
  for (int i = 0; i < 200; ++i) sim.step({{0.5, 5.0, 0.5}, Quat{}});
  // Every pair of neighbours along X is within the repose slope (plus the
  // relaxation tolerance, 2 % of it) of each other.
  const double limit = std::tan(34.0 * std::numbers::pi / 180.0) * p.grid.cell_x_m() * 1.02 + 1e-6;
  for (int r = 0; r < 21; ++r)
    for (int c = 0; c + 1 < 21; ++c)
      EXPECT_LE(std::abs(sim.grid().height(c, r) - sim.grid().height(c + 1, r)), limit);
  EXPECT_LT(sim.grid().height(10, 10), spike / 2);
  EXPECT_NEAR(sim.grid().volume_m3(), volume, 1e-6 * volume);
}

}  // namespace
}  // namespace terracut
