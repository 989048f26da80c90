// SPDX-License-Identifier: Apache-2.0
#include "physics/ode_handles.hpp"

#include <mutex>

namespace ubersim::kernel {
namespace {
// ODE's init state is process-wide; the count mirrors it so the last world closes ODE.
std::mutex& InitMutex() { static std::mutex m; return m; }
int& InitCount() { static int n = 0; return n; }
}  // namespace

OdeLibrary::OdeLibrary() {
  std::lock_guard lock(InitMutex());
  if (InitCount()++ == 0) dInitODE2(0);
}

OdeLibrary::~OdeLibrary() {
  std::lock_guard lock(InitMutex());
  if (--InitCount() == 0) dCloseODE();
}

}  // namespace ubersim::kernel
