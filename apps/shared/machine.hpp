// SPDX-License-Identifier: Apache-2.0
// The machine a figure was measured on, and the process's memory: for bench, batch and soak reports.
#pragma once

#include <string>

namespace ubersim::apps {

/// The machine and build the figures came from (CPU, cores, OS, compiler, ODE).
std::string MachineDescription();

/// Resident memory now and at its peak, MB (from /proc/self/status; 0 where unavailable).
double ResidentMegabytes();
double PeakResidentMegabytes();  ///< the process's peak resident memory, MB

}  // namespace ubersim::apps
