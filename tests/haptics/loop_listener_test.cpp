// The haptic loop with a step listener on its simulation (a test listener,
// no physics): when it is called (on_step on every stepped tick and only
// then, on_lift on a reconnection, its bodies read before each publish), how
// its force joins the world force and is scaled to the device like the force
// models', and the bodies it writes into viewer frames.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "haptics_fixture.hpp"
#include "terracut/haptics/loop.hpp"
#include "terracut/haptics/script_device.hpp"

namespace terracut::haptics {
namespace {

using test::trench;

// A listener that pushes back on the tool with a fixed world force while the
// tool is below `below_y_m`, says it has two bodies, and records every call.
class TestEngine final : public StepListener, public BodySource {
 public:
  Vec3 force_n{0.0, 0.0, 0.0};
  double below_y_m = 1e9;
  const Simulation* sim = nullptr;
  int attached = 0, lifts = 0, detached = 0;
  mutable int fills = 0;
  std::int64_t steps = 0;
  std::int64_t last_step = -1;
  Vec3 last_tool_m{};

  void attach(Simulation& s) {
    ++attached;
    sim = &s;
    s.add_listener(*this);
  }
  void detach() {
    ++detached;
    const_cast<Simulation*>(sim)->remove_listener(*this);
    sim = nullptr;
  }
  Vec3 on_step(const StepOutput& out) noexcept override {
    ++steps;
    last_step = out.step;
    last_tool_m = out.pose.position_m;
    return out.pose.position_m.y < below_y_m ? force_n : Vec3{};
  }
  void on_lift() noexcept override { ++lifts; }
  int body_total() const noexcept override { return 2; }
  int write_bodies(std::span<BodyView> out) const noexcept override {
    ++fills;
    // One sphere riding on the tool, and a box at the origin.
    out[0].shape = BodyShape::kSphere;
    out[0].half_extents_m = {0.05, 0.05, 0.05};
    out[0].position_m = last_tool_m;
    out[1].shape = BodyShape::kBox;
    out[1].half_extents_m = {0.1, 0.2, 0.3};
    out[1].position_m = {};
    out[1].orientation = {};
    return 2;
  }
};

// A loop whose simulation has the engine as its listener (attached before
// the first tick, detached when the rig goes), and its bodies for the frames.
struct EngineRig {
  test::LoopRig rig;
  TestEngine* engine = nullptr;
  ~EngineRig() {
    if (engine) {
      rig.loop.reset();
      engine->detach();
    }
  }
};

// The rig, used through its loop.
struct EngineLoop {
  std::unique_ptr<EngineRig> rig;
  HapticLoop* operator->() const { return rig->rig.loop.get(); }
};

const Motion& trench_cut() { return trench().scenario.cuts[0]; }

std::int64_t ticks_of(const HapticSettings& s) {
  return std::llround((trench_cut().duration_s() + s.settle_s) * trench().scenario.rate_hz);
}

EngineLoop make_loop(Device& device, std::int64_t ticks, TestEngine* engine,
                     SnapshotExchange* snapshot = nullptr) {
  const io::Scenario& sc = trench().scenario;
  LoopOptions o = test::test_loop_options(ticks, snapshot);
  o.bodies = engine;
  auto r = std::make_unique<EngineRig>();
  r->rig = test::make_loop_rig(trench().haptics, sc, trench_cut().keyframes[0].pose.orientation,
                               device, o);
  if (engine) {
    engine->attach(*r->rig.sim);
    r->engine = engine;
  }
  return {std::move(r)};
}

TEST(LoopListener, ForceJoinsTheWorldForceAndIsScaledToTheDeviceTheSameWay) {
  const HapticSettings& s = trench().haptics;
  const std::int64_t ticks = ticks_of(s);
  // A force against the cut's motion (-Z) and sideways, while the blade is in
  // the sand (the sand's top is at 0.3 m).
  TestEngine engine;
  engine.force_n = {30.0, 0.0, 150.0};
  engine.below_y_m = 0.3;
  std::vector<LoopRecord> with, without;
  {
    ScriptDevice device(DevicePath(trench_cut(), Workspace(s.workspace)));
    auto loop = make_loop(device, ticks, &engine);
    EXPECT_EQ(engine.attached, 1);
    EXPECT_EQ(engine.sim, &loop->simulation());  // a listener of the loop's simulation
    loop->run_deterministic();
    with = loop->records();
    EXPECT_EQ(engine.steps, ticks);  // every tick was stepped (the script never fails)
    EXPECT_EQ(engine.last_step, loop->simulation().last().step);
    EXPECT_EQ(engine.lifts, 0);
    EXPECT_EQ(engine.fills, 0);  // no snapshot exchange
    EXPECT_DOUBLE_EQ(loop->max_body_force_n(), length(engine.force_n));
    EXPECT_EQ(engine.detached, 0);
  }
  EXPECT_EQ(engine.detached, 1);  // removed when the loop went
  EXPECT_EQ(engine.sim, nullptr);
  {
    ScriptDevice device(DevicePath(trench_cut(), Workspace(s.workspace)));
    auto loop = make_loop(device, ticks, nullptr);
    loop->run_deterministic();
    without = loop->records();
    EXPECT_EQ(loop->max_body_force_n(), 0.0);
  }
  ASSERT_EQ(with.size(), without.size());
  int pushed = 0, unlimited = 0;
  for (std::size_t i = 0; i < with.size(); ++i) {
    const LoopRecord& a = with[i];
    const LoopRecord& b = without[i];
    ASSERT_EQ(a.tool.position_m.y, b.tool.position_m.y) << i;  // the same path
    EXPECT_EQ(length(b.body_force_world_n), 0.0) << i;
    const bool in_sand = a.tool.position_m.y < 0.3;
    const Vec3 expected = in_sand ? engine.force_n : Vec3{};
    EXPECT_EQ(a.body_force_world_n.x, expected.x) << i;
    EXPECT_EQ(a.body_force_world_n.z, expected.z) << i;
    // The world force is the models' plus the engine's.
    const Vec3 d = a.force_world_n - b.force_world_n;
    EXPECT_NEAR(d.x, expected.x, 1e-9 * (1.0 + length(a.force_world_n))) << i;
    EXPECT_NEAR(d.y, expected.y, 1e-9 * (1.0 + length(a.force_world_n))) << i;
    EXPECT_NEAR(d.z, expected.z, 1e-9 * (1.0 + length(a.force_world_n))) << i;
    if (!in_sand) {
      EXPECT_EQ(a.force_device_n.x, b.force_device_n.x) << i;  // nothing else changed
      EXPECT_EQ(a.force_device_n.z, b.force_device_n.z) << i;
    }
    if (in_sand) ++pushed;
    // Where the safety limiter left it alone, the device force is the whole
    // world force times force_scale (the device frame turns, not scales).
    if (a.flags == 0) {
      ++unlimited;
      EXPECT_NEAR(length(a.force_device_n), length(a.force_world_n) * s.forces.force_scale, 1e-9)
          << i;
    }
  }
  EXPECT_GT(pushed, 1000);
  EXPECT_GT(unlimited, 1000);
}

TEST(LoopListener, NotCalledWhenTheSimulationIsNotStepped) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice script(DevicePath(trench_cut(), Workspace(s.workspace)));
  // Ten NaN samples in the cut: the simulation (and so the engine) stands still.
  test::FaultyDevice device(
      script, [](std::int64_t tick) { return tick >= 2000 && tick < 2010; }, nullptr);
  TestEngine engine;
  engine.force_n = {0.0, 0.0, 100.0};
  const std::int64_t ticks = 2500;
  auto loop = make_loop(device, ticks, &engine);
  loop->run_deterministic();
  EXPECT_EQ(loop->counters().bad_samples, 10);
  EXPECT_EQ(engine.steps, ticks - 10);
  const std::vector<LoopRecord> rs = loop->records();
  for (int i = 2000; i < 2010; ++i) {
    EXPECT_EQ(length(rs[std::size_t(i)].body_force_world_n), 0.0) << i;
    EXPECT_EQ(length(rs[std::size_t(i)].force_device_n), 0.0) << i;
  }
  EXPECT_EQ(rs[2010].body_force_world_n.z, 100.0);
}

// A script device whose sample at one tick says the device reconnected.
class ReconnectingDevice final : public Device {
 public:
  ReconnectingDevice(Device& inner, std::int64_t at) : inner_(inner), at_(at) {}
  std::string_view kind() const override { return inner_.kind(); }
  void start(double t_s) override { inner_.start(t_s); }
  bool read(double t_s, DeviceSample& out) noexcept override {
    const bool got = inner_.read(t_s, out);
    out.reconnected = reads_++ == at_;
    return got;
  }
  void write(const DeviceCommand& c) noexcept override { inner_.write(c); }

 private:
  Device& inner_;
  std::int64_t at_;
  std::int64_t reads_ = 0;
};

TEST(LoopListener, LiftedWhenTheDeviceReconnects) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice script(DevicePath(trench_cut(), Workspace(s.workspace)));
  ReconnectingDevice device(script, 1500);
  TestEngine engine;
  auto loop = make_loop(device, 2000, &engine);
  loop->run_deterministic();
  EXPECT_EQ(loop->counters().reconnects, 1);
  EXPECT_EQ(engine.lifts, 1);
  EXPECT_EQ(engine.steps, 2000);
}

TEST(LoopListener, FillsTheBodiesOfEveryPublishedFrame) {
  const HapticSettings& s = trench().haptics;
  const io::Scenario& sc = trench().scenario;
  const std::int64_t ticks = 1800;
  HeightGrid grid(io::grid_spec(sc), io::build_initial_heights(sc));
  SnapshotExchange exchange(grid);
  EXPECT_EQ(exchange.front().body_count, 0);  // none before the listener speaks
  TestEngine engine;
  ScriptDevice device(DevicePath(trench_cut(), Workspace(s.workspace)));
  auto loop = make_loop(device, ticks, &engine, &exchange);
  loop->run_deterministic();
  EXPECT_EQ(engine.fills, ticks);
  const ViewFrame* f = exchange.acquire();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->sequence, std::uint64_t(ticks));
  ASSERT_EQ(f->body_count, 2);
  EXPECT_EQ(f->body_total, 2);
  EXPECT_EQ(f->bodies[0].shape, BodyShape::kSphere);
  // The sphere rides on the tool: the frame holds the last tick's pose.
  EXPECT_EQ(f->bodies[0].position_m.x, loop->last().tool.position_m.x);
  EXPECT_EQ(f->bodies[0].position_m.y, loop->last().tool.position_m.y);
  EXPECT_EQ(f->bodies[0].position_m.z, loop->last().tool.position_m.z);
  EXPECT_EQ(f->bodies[1].shape, BodyShape::kBox);
  EXPECT_EQ(f->bodies[1].half_extents_m.z, 0.3);

  // Without an engine the frames carry no bodies.
  SnapshotExchange plain(grid);
  ScriptDevice device2(DevicePath(trench_cut(), Workspace(s.workspace)));
  auto loop2 = make_loop(device2, 10, nullptr, &plain);
  loop2->run_deterministic();
  const ViewFrame* g = plain.acquire();
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(g->body_count, 0);
  EXPECT_EQ(g->body_total, 0);
}

}  // namespace
}  // namespace terracut::haptics
