// SPDX-License-Identifier: Apache-2.0
// The SimulatorError codes this transport sends. They are part of the wire interface: stable,
// documented in docs/interfaces.md, never renamed.
#pragma once

namespace ubersim::ssl_simulation::codes {

// The datagram or frame itself.
inline constexpr char kUnreadable[] = "UBERSIM_UNREADABLE";        // not a parseable message
inline constexpr char kOversized[] = "UBERSIM_OVERSIZED";          // larger than max_message_size
inline constexpr char kMissingField[] = "UBERSIM_MISSING_FIELD";   // a required field is unset

// Well-formed but wrong: the whole message is refused, nothing of it is applied.
inline constexpr char kNonFinite[] = "UBERSIM_NON_FINITE";         // NaN or infinity
inline constexpr char kUnknownRobot[] = "UBERSIM_UNKNOWN_ROBOT";   // no such robot in the world
inline constexpr char kInvalidTeam[] = "UBERSIM_INVALID_TEAM";     // team unset or UNKNOWN
inline constexpr char kPartialCoord[] = "UBERSIM_PARTIAL_COORD";   // only one of x, y
inline constexpr char kInvalidValue[] = "UBERSIM_INVALID_VALUE";   // out of its allowed range

// Not supported: that item is skipped, the rest of the message is applied.
inline constexpr char kTeleportSafely[] = "UBERSIM_UNSUPPORTED_TELEPORT_SAFELY";
inline constexpr char kByForce[] = "UBERSIM_UNSUPPORTED_BY_FORCE";
inline constexpr char kGeometry[] = "UBERSIM_UNSUPPORTED_GEOMETRY";
inline constexpr char kRobotSpecs[] = "UBERSIM_UNSUPPORTED_ROBOT_SPECS";
inline constexpr char kVisionPort[] = "UBERSIM_UNSUPPORTED_VISION_PORT";
inline constexpr char kUnknownRealism[] = "UBERSIM_UNKNOWN_REALISM_TYPE";
inline constexpr char kRealismFields[] = "UBERSIM_UNSUPPORTED_REALISM_FIELDS";
inline constexpr char kWheelVelocity[] = "UBERSIM_UNSUPPORTED_WHEEL_VELOCITY";

// Synchronous mode.
inline constexpr char kSyncStep[] = "UBERSIM_SYNC_INVALID_STEP";   // sim_step not in (0, max]
inline constexpr char kSyncTimeout[] = "UBERSIM_SYNC_TIMEOUT";     // the world did not step in time

}  // namespace ubersim::ssl_simulation::codes
