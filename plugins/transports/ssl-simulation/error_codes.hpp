// SPDX-License-Identifier: Apache-2.0
// The SimulatorError codes this transport sends. They are part of the wire interface: stable,
// documented in docs/interfaces.md, never renamed.
#pragma once

namespace ubersim::ssl_simulation::codes {

// The datagram or frame itself: nothing of it can be trusted, nothing is applied.
inline constexpr char kUnreadable[] = "UBERSIM_UNREADABLE";        // not a parseable message
inline constexpr char kOversized[] = "UBERSIM_OVERSIZED";          // larger than max_message_size

// One item is wrong (a teleport, a robot's command, a spec, a setting): that item is skipped
// with one error naming it, the rest of the message is applied.
inline constexpr char kMissingField[] = "UBERSIM_MISSING_FIELD";   // a required field is unset
inline constexpr char kNonFinite[] = "UBERSIM_NON_FINITE";         // NaN or infinity
inline constexpr char kUnknownRobot[] = "UBERSIM_UNKNOWN_ROBOT";   // no such robot on the field
inline constexpr char kInvalidRobotId[] = "UBERSIM_INVALID_ROBOT_ID";  // not 0..15
inline constexpr char kInvalidTeam[] = "UBERSIM_INVALID_TEAM";     // team unset or UNKNOWN
inline constexpr char kPartialCoord[] = "UBERSIM_PARTIAL_COORD";   // only one of x, y
inline constexpr char kInvalidValue[] = "UBERSIM_INVALID_VALUE";   // out of its allowed range
inline constexpr char kCreateNoPosition[] = "UBERSIM_CREATE_NO_POSITION";  // present: true for a new robot without x, y
inline constexpr char kRobotNotBuilt[] = "UBERSIM_ROBOT_NOT_BUILT";  // the world could not build or place the robot
inline constexpr char kInvalidSpec[] = "UBERSIM_INVALID_SPEC";     // a robot_specs value the model refuses
inline constexpr char kUnmappedSpec[] = "UBERSIM_UNMAPPED_SPEC_FIELDS";  // robot_specs fields the model has no place for
inline constexpr char kGeometry[] = "UBERSIM_GEOMETRY_NOT_APPLIED";  // no known field of that size
inline constexpr char kVisionPort[] = "UBERSIM_VISION_PORT_NOT_APPLIED";  // no vision transport took it

// Not supported: that item is skipped, the rest of the message is applied.
inline constexpr char kTeleportSafely[] = "UBERSIM_UNSUPPORTED_TELEPORT_SAFELY";
inline constexpr char kByForce[] = "UBERSIM_UNSUPPORTED_BY_FORCE";
inline constexpr char kUnknownRealism[] = "UBERSIM_UNKNOWN_REALISM_TYPE";
// No longer sent: every RealismConfigErForce field is applied. Kept so the code is never reused.
inline constexpr char kRealismFields[] = "UBERSIM_UNSUPPORTED_REALISM_FIELDS";
inline constexpr char kWheelVelocity[] = "UBERSIM_UNSUPPORTED_WHEEL_VELOCITY";

// Synchronous mode.
inline constexpr char kSyncStep[] = "UBERSIM_SYNC_INVALID_STEP";   // sim_step not in (0, max]
inline constexpr char kSyncTimeout[] = "UBERSIM_SYNC_TIMEOUT";     // the world did not step in time

}  // namespace ubersim::ssl_simulation::codes
