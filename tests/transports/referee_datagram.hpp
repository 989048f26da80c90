// SPDX-License-Identifier: Apache-2.0
// A Referee datagram for the viewer's end-to-end tests, built apart from them: the generated
// protobuf classes live in the global namespace (RobotId, Team) and would clash with ubersim's.
#pragma once

#include <cstdint>
#include <string>

namespace ubersim::testing {

/// A serialized Referee message of a stoppage in the first half: STOP (counter 3), next
/// DIRECT_FREE_YELLOW at (-1200, 800) mm, yellow 1 : 0 blue, one yellow card for blue with 45 s
/// left, the last event BALL_LEFT_FIELD_TOUCH_LINE by blue, `stage_time_left_us` of the half left.
std::string StopRefereeDatagram(const std::string& yellow, const std::string& blue, std::int64_t stage_time_left_us);

}  // namespace ubersim::testing
