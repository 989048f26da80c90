// SPDX-License-Identifier: Apache-2.0
#include "shared/machine.hpp"

#include <sys/utsname.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "ubersim/kernel/world.hpp"

namespace ubersim::apps {
namespace {

double StatusKilobytes(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(key) + ":";
  while (std::getline(f, line)) {
    if (line.rfind(prefix, 0) == 0) return std::atof(line.c_str() + prefix.size());
  }
  return 0.0;
}

std::string CpuModel() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  }
  return "unknown CPU";
}

}  // namespace

double ResidentMegabytes() { return StatusKilobytes("VmRSS") / 1024.0; }
double PeakResidentMegabytes() { return StatusKilobytes("VmHWM") / 1024.0; }

std::string MachineDescription() {
  std::ostringstream out;
  utsname u{};
  uname(&u);
  out << CpuModel() << ", " << sysconf(_SC_NPROCESSORS_ONLN) << " cores online; " << u.sysname << " "
      << u.release << "; compiler " << __VERSION__;
#ifdef NDEBUG
  out << ", optimised build";
#else
  out << ", debug build (assertions on)";
#endif
  out << "; ODE configuration: " << kernel::PhysicsEngineConfiguration();
  return out.str();
}

}  // namespace ubersim::apps
