// SPDX-License-Identifier: Apache-2.0
#include "physics/island_stepper.hpp"

#include <algorithm>

namespace ubersim::kernel {
namespace {

// The body `j` links `b` to (null: the static world).
dBodyID OtherBody(dJointID j, dBodyID b) {
  return dJointGetBody(j, 0) == b ? dJointGetBody(j, 1) : dJointGetBody(j, 0);
}

// Calls f(other) for each body `b` is linked to through an enabled joint, in the order of b's
// joint list (QuickStep's island search follows the same links in the same order). A joint to
// the static world links no body.
template <typename F>
void ForEachLinkedBody(dBodyID b, F&& f) {
  for (int k = 0;; ++k) {
    dJointID j = dBodyGetJoint(b, k);
    if (!j) return;
    if (!dJointIsEnabled(j)) continue;
    if (dBodyID other = OtherBody(j, b)) f(other);
  }
}

}  // namespace

std::vector<char> FindLimbs(const std::vector<dBodyID>& bodies) {
  std::vector<char> limbs(bodies.size(), 0);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    for (int k = 0;; ++k) {
      dJointID j = dBodyGetJoint(bodies[i], k);
      if (!j) break;
      if (dJointGetType(j) == dJointTypeContact) continue;  // made and dropped every step
      dBodyID other = OtherBody(j, bodies[i]);
      // Newest first: a body created before this one comes after it.
      if (other && std::find(bodies.begin() + i + 1, bodies.end(), other) != bodies.end()) {
        limbs[i] = 1;
        break;
      }
    }
  }
  return limbs;
}

void IslandStepper::SetIterations(int ball_islands, int other_islands) {
  ball_iterations_ = std::max(1, ball_islands);
  other_iterations_ = std::max(1, other_islands);
}

bool IslandStepper::InBallIslands(dBodyID b) const {
  // A ball's island is a handful of bodies (the ball, a robot or two): a scan beats a hash set.
  return std::find(ball_islands_.begin(), ball_islands_.end(), b) != ball_islands_.end();
}

void IslandStepper::FindBallIslands(const std::vector<dBodyID>& balls) {
  ball_islands_.clear();
  for (dBodyID ball : balls) {
    if (!InBallIslands(ball)) ball_islands_.push_back(ball);
  }
  // Breadth first over the growing list: the same links QuickStep's island search follows.
  for (std::size_t next = 0; next < ball_islands_.size(); ++next) {
    ForEachLinkedBody(ball_islands_[next], [this](dBodyID other) {
      if (!InBallIslands(other)) ball_islands_.push_back(other);
    });
  }
}

bool IslandStepper::InPass(std::size_t index, bool ball_pass) const {
  return !split_ || static_cast<bool>(in_ball_islands_[index]) == ball_pass;
}

void IslandStepper::Step(dWorldID world, const std::vector<dBodyID>& bodies, const std::vector<dBodyID>& balls,
                         double dt, const std::vector<char>& limbs) {
  limbs_ = limbs.size() == bodies.size() ? &limbs : nullptr;
  dWorldGetGravity(world, gravity_);
  split_ = ball_iterations_ != other_iterations_ && !balls.empty();
  if (!split_) {
    Pass(world, bodies, true, ball_iterations_, dt);
  } else {
    // First the ball's islands, then the rest. Islands are disconnected, so QuickStep's search
    // from the enabled bodies never reaches a paused one. QuickStep may enable a disabled body a
    // ball's island reached, as one QuickStep would have: it stays enabled for the second pass,
    // which it sits out.
    FindBallIslands(balls);
    in_ball_islands_.resize(bodies.size());
    for (std::size_t i = 0; i < bodies.size(); ++i) in_ball_islands_[i] = InBallIslands(bodies[i]);
    Pass(world, bodies, true, ball_iterations_, dt);
    Pass(world, bodies, false, other_iterations_, dt);
  }
  limbs_ = nullptr;  // the caller's, valid for this call only
}

void IslandStepper::Pass(dWorldID world, const std::vector<dBodyID>& bodies, bool ball_pass, int iterations,
                         double dt) {
  paused_.clear();
  lone_.clear();
  held_.clear();
  std::size_t solved = 0;  // enabled bodies of this pass linked by a joint: QuickStep's work
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    dBodyID b = bodies[i];
    if (!dBodyIsEnabled(b)) continue;
    if (!InPass(i, ball_pass)) {
      paused_.push_back(b);
    } else if (IsLoneBody(b)) {
      lone_.push_back(b);
    } else {
      ++solved;
      if (IsLimb(i)) held_.push_back(b);  // a limb has a joint: never lone
    }
  }
  if (solved > 0 && !lone_.empty()) {
    // QuickStep would have moved the lone bodies between its other islands: the broadphase
    // lists the geometries in the order they first moved, and that order decides which contact
    // comes first. Touching every body of the pass in QuickStep's order first keeps those lists
    // as they were; the moves that follow do not reorder what is listed already. The touch
    // costs about a tenth of what a lone body saves: for a ball in flight among a hundred wheel
    // bodies, QuickStep keeps it (the same numbers either way).
    if (lone_.size() * 10 < solved) {
      lone_.clear();
    } else {
      TouchInQuickStepOrder(bodies, ball_pass);
    }
  }
  for (dBodyID b : lone_) {
    lone_stepper_.Step(b, gravity_, dt);
    paused_.push_back(b);  // stepped: QuickStep must not step it again
  }
  if (solved == 0) return;
  for (dBodyID b : paused_) dBodyDisable(b);
  // A disabled body starts no island, and the search enables every body it reaches through a
  // joint: a disabled limb joins its island where the search meets it, after its root's joints.
  for (dBodyID b : held_) dBodyDisable(b);
  dWorldSetQuickStepNumIterations(world, iterations);
  dWorldQuickStep(world, dt);
  for (dBodyID b : paused_) dBodyEnable(b);
  // Only a limb whose joints were taken away since FindLimbs is still disabled: it sat this step
  // out, and is enabled for the next rather than left behind.
  for (dBodyID b : held_) {
    if (!dBodyIsEnabled(b)) dBodyEnable(b);
  }
}

void IslandStepper::TouchInQuickStepOrder(const std::vector<dBodyID>& bodies, bool ball_pass) {
  // QuickStep's island search (ODE's util.cpp): down its body list, each enabled body not yet
  // reached starts an island; a stack walks the bodies' joint lists in order, through enabled
  // joints, and the island's bodies are stepped in the order the walk reaches them. (ODE also
  // marks the joints it crossed; crossing one again leads to a body already reached, so the
  // order needs no such mark.) A pass mixing lone bodies and QuickStep's islands is a few dozen
  // bodies at most: a scan of the reached ones beats a hash set's allocations.
  reached_.clear();
  auto reach = [this](dBodyID b) {
    if (std::find(reached_.begin(), reached_.end(), b) != reached_.end()) return false;
    reached_.push_back(b);
    return true;
  };
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    dBodyID b = bodies[i];
    // A limb starts no island (Pass holds it back): its root's walk reaches it.
    if (!dBodyIsEnabled(b) || !InPass(i, ball_pass) || IsLimb(i) || !reach(b)) continue;
    walk_.clear();
    while (true) {
      const dReal* p = dBodyGetPosition(b);
      dBodySetPosition(b, p[0], p[1], p[2]);  // the same position: only its geometries are told
      ForEachLinkedBody(b, [&](dBodyID other) {
        if (reach(other)) walk_.push_back(other);
      });
      if (walk_.empty()) break;
      b = walk_.back();
      walk_.pop_back();
    }
  }
}

}  // namespace ubersim::kernel
