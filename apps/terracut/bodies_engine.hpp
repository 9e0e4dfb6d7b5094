// Rigid bodies in the haptic loop: a haptics::LoopEngine that steps a Bullet
// TerrainWorld (include/terracut/bullet/terrain_world.hpp) over the loop's
// own simulation, so that the force the bodies put on the blade's plate joins
// the haptic feedback (an operator feels the blade hit a rock) and the
// viewer's frames carry the bodies' poses.
//
// Shared by `terracut haptics` and terracut-viewer (one static library,
// terracut_bodies_engine, built in apps/terracut). The haptics layer knows
// nothing of Bullet: this engine is attached through HapticLoop's LoopEngine
// hook. Built without Bullet, make_bodies_engine() throws an InputError that
// says so.
//
// Per tick (on the loop's thread, allocation-free once Bullet is warm):
// TerrainWorld::step(out) (terrain change -> plate to the blade pose -> one
// Bullet step of 1 / rate), then the tool force of that step is returned to
// the loop, and a row per body goes to bodies.csv when one is written
// (bullet::BodiesCsvWriter: a 64 KiB buffer written to the file when full).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "terracut/core/bodies.hpp"
#include "terracut/haptics/loop.hpp"

namespace terracut::apps {

/// What a bodies engine writes.
struct BodiesEngineOptions {
  /// bodies.csv (bullet/bodies_csv.hpp format): the bodies' state before the
  /// first step (t = 0) and after every step; empty: no file. The folder must
  /// exist; the file is created when the engine is attached to a loop.
  std::filesystem::path csv_path;
};

/// True when this build has the Bullet engine (make_bodies_engine works).
bool bodies_engine_available();

/// The message of the InputError a build without Bullet throws for a
/// scenario with bodies.
std::string bodies_engine_unavailable_message();

/// A LoopEngine that simulates `bodies` with Bullet on the loop's terrain.
/// The bodies are checked when the engine is attached (HapticLoop's
/// constructor: InputError naming the body). Throws InputError
/// (bodies_engine_unavailable_message()) when this build has no Bullet.
std::unique_ptr<haptics::LoopEngine> make_bodies_engine(std::vector<BodySpec> bodies,
                                                        const BodiesEngineOptions& options = {});

}  // namespace terracut::apps
