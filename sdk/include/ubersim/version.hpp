// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>

namespace ubersim {
inline namespace v1 {

/// SDK major version: plugins built against another major are refused.
inline constexpr std::uint32_t kSdkVersionMajor = 0;
/// SDK minor version: a plugin needing a newer minor than the kernel's is refused.
inline constexpr std::uint32_t kSdkVersionMinor = 1;
/// Version of the binary plugin boundary (descriptor layout, interface vtables).
inline constexpr std::uint32_t kPluginAbiVersion = 12;  // 2: RealismEvent joined the Event variant; 3: GeomSpec::scope; 4: SurfaceMaterial::surface_velocity; 5: RobotContext::CarpetSurface; 6: JointSpec::measure_torque; 7: TransportContext::LocalOnly and the robot, field and vision-port events (the drop-in issue); 8: GeomSpec::friction_axis_turn (rollers at any angle: mecanum); 9: RobotState::drive (a drive's feedback in the ground truth); 10: Drive::Placed (after a teleport); 11: Body::AddFixedMass (wheels without bodies); 12: the league's realism fields (RealismEvent, DetectedBall::area)

/// The ABI word a plugin exports and the kernel reads before calling anything: abi << 16 | sdk major.
inline constexpr std::uint32_t kPluginAbiWord = (kPluginAbiVersion << 16) | kSdkVersionMajor;

}  // namespace v1
}  // namespace ubersim
