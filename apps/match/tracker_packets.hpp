// SPDX-License-Identifier: Apache-2.0
// Tracked vision (TrackerWrapperPacket, ssl-protocols.md §1.11) from the simulated truth: what an
// ideal tracker would report, in metres and Unix seconds.
#pragma once

#include <cstdint>
#include <random>
#include <string>

#include <ubersim/world_state.hpp>

#include "ssl_vision_wrapper_tracked.pb.h"

namespace ubersim::match {

/// Who sends the tracked frames.
struct TrackerSource {
  std::string uuid;                          ///< random and fixed per source (the league's readers key on it)
  std::string name = "UberSim ground truth";  ///< source_name
};

/// Gaussian noise on tracked positions (the perception pipeline's σ), drawn from `rng`.
struct TrackerNoise {
  double ball_position_sigma = 0;      ///< m
  double robot_position_sigma = 0;     ///< m
  double robot_orientation_sigma = 0;  ///< rad
  std::mt19937_64* rng = nullptr;      ///< the stream to draw from (seeded by the caller)
};

/// One tracked frame of `truth`: the ball (visibility 1) and every robot on the field, with
/// velocities; `unix_offset_ns` turns simulated time into the Unix time stamp. With `noise`, the
/// positions and orientations carry it (velocities stay true).
TrackerWrapperPacket TrackedPacket(const WorldSnapshot& truth, std::uint32_t frame_number, std::int64_t unix_offset_ns,
                                   const TrackerSource& source, const TrackerNoise* noise = nullptr);

/// A version-4-shaped UUID drawn from `seed` (deterministic: the same world gives the same id).
std::string UuidFromSeed(std::uint64_t seed);

}  // namespace ubersim::match
