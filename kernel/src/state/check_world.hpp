// SPDX-License-Identifier: Apache-2.0
// The state checks on a world's insides: what the public CheckState runs, and what the world
// itself runs on its own implementation (finding non-finite bodies after a step).
#pragma once

#include <vector>

#include "ubersim/kernel/state_check.hpp"

namespace ubersim::kernel {

class WorldImpl;

/// CheckState (state_check.hpp) on a world's implementation.
std::vector<StateViolation> CheckState(const WorldImpl& world, const StateCheckOptions& options);

}  // namespace ubersim::kernel
