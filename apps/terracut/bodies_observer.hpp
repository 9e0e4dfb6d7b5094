// `terracut run` with rigid bodies: the Bullet world follows the run and
// writes DIR/bodies.csv (and a summary entry).
#pragma once

#include <memory>
#include <vector>

#include "terracut/core/bodies.hpp"
#include "terracut/io/run.hpp"

namespace terracut::cli {

/// A run observer that steps a Bullet world over the simulation's terrain, or
/// nullptr (with an InputError) when this build has no Bullet.
std::unique_ptr<io::RunObserver> make_bodies_observer(const std::vector<BodySpec>& bodies);

}  // namespace terracut::cli
