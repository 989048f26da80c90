// SPDX-License-Identifier: Apache-2.0
#pragma once
/// Everything a plugin needs, in one include.
#include "ubersim/component.hpp"
#include "ubersim/events.hpp"
#include "ubersim/log.hpp"
#include "ubersim/math.hpp"
#include "ubersim/params.hpp"
#include "ubersim/plugin.hpp"
#include "ubersim/scene.hpp"
#include "ubersim/servo.hpp"
#include "ubersim/state_io.hpp"
#include "ubersim/transport.hpp"
#include "ubersim/version.hpp"
#include "ubersim/wheel.hpp"
#include "ubersim/world_state.hpp"
