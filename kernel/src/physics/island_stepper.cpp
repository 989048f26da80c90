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

void IslandStepper::GroupByDemand(const std::vector<dBodyID>& bodies, const std::vector<dBodyID>& balls,
                                  const std::vector<IterationDemand>& demands) {
  seeds_.clear();
  for (dBodyID ball : balls) seeds_.push_back({ball, ball_iterations_});
  for (const IterationDemand& d : demands) {
    if (d.body && d.iterations > other_iterations_) seeds_.push_back(d);
  }
  // The highest count first, so an island reached from two seeds gets the higher; balls before
  // demands of the same count. Stable, by insertion: a few dozen seeds, mostly in order, and
  // std::stable_sort would allocate its buffer every step.
  for (std::size_t i = 1; i < seeds_.size(); ++i) {
    const IterationDemand moving = seeds_[i];
    std::size_t j = i;
    for (; j > 0 && seeds_[j - 1].iterations < moving.iterations; --j) seeds_[j] = seeds_[j - 1];
    seeds_[j] = moving;
  }
  pass_iterations_.clear();
  marked_.clear();
  const auto pass_of = [this](int iterations) {
    const auto it = std::find(pass_iterations_.begin(), pass_iterations_.end(), iterations);
    if (it != pass_iterations_.end()) return static_cast<int>(it - pass_iterations_.begin());
    pass_iterations_.push_back(iterations);
    return static_cast<int>(pass_iterations_.size()) - 1;
  };
  const auto marked = [this](dBodyID b) {
    return std::any_of(marked_.begin(), marked_.end(), [b](const auto& m) { return m.first == b; });
  };
  for (const IterationDemand& seed : seeds_) {
    if (marked(seed.body)) continue;  // its island has a count already, as high or higher
    const int pass = pass_of(seed.iterations);
    // Breadth first over the island, as FindBallIslands: the links QuickStep's search follows.
    const std::size_t first = marked_.size();
    marked_.push_back({seed.body, pass});
    for (std::size_t next = first; next < marked_.size(); ++next) {
      ForEachLinkedBody(marked_[next].first, [&](dBodyID other) {
        if (!marked(other)) marked_.push_back({other, pass});
      });
    }
  }
  // The few marked bodies looked up in the list, not the list in them (each body is listed once).
  group_.assign(bodies.size(), -1);
  std::size_t grouped = 0;
  for (const auto& [body, pass] : marked_) {
    const auto at = std::find(bodies.begin(), bodies.end(), body);
    if (at == bodies.end()) continue;
    group_[static_cast<std::size_t>(at - bodies.begin())] = pass;
    ++grouped;
  }
  // Every body not reached from a seed takes the other islands' count: the pass after the
  // seeds' (pass_of adds it, if no seed has that count).
  if (grouped == bodies.size()) return;
  const int other = pass_of(other_iterations_);
  for (int& g : group_) {
    if (g < 0) g = other;
  }
}

void IslandStepper::Step(dWorldID world, const std::vector<dBodyID>& bodies, const std::vector<dBodyID>& balls,
                         double dt, const std::vector<char>& limbs, const std::vector<IterationDemand>& demands) {
  limbs_ = limbs.size() == bodies.size() ? &limbs : nullptr;
  dWorldGetGravity(world, gravity_);
  const bool demanding = std::any_of(demands.begin(), demands.end(), [this](const IterationDemand& d) {
    return d.body && d.iterations > other_iterations_;
  });
  if (demanding) {
    GroupByDemand(bodies, balls, demands);
    split_ = pass_iterations_.size() > 1;
    for (std::size_t pass = 0; pass < pass_iterations_.size(); ++pass) {
      Pass(world, bodies, static_cast<int>(pass), pass_iterations_[pass], dt);
    }
    limbs_ = nullptr;
    return;
  }
  split_ = ball_iterations_ != other_iterations_ && !balls.empty();
  if (!split_) {
    Pass(world, bodies, 0, ball_iterations_, dt);
  } else {
    // First the ball's islands, then the rest. Islands are disconnected, so QuickStep's search
    // from the enabled bodies never reaches a paused one. QuickStep may enable a disabled body a
    // ball's island reached, as one QuickStep would have: it stays enabled for the second pass,
    // which it sits out.
    FindBallIslands(balls);
    group_.resize(bodies.size());
    for (std::size_t i = 0; i < bodies.size(); ++i) group_[i] = InBallIslands(bodies[i]) ? 0 : 1;
    Pass(world, bodies, 0, ball_iterations_, dt);
    Pass(world, bodies, 1, other_iterations_, dt);
  }
  limbs_ = nullptr;  // the caller's, valid for this call only
}

void IslandStepper::Pass(dWorldID world, const std::vector<dBodyID>& bodies, int pass, int iterations,
                         double dt) {
  paused_.clear();
  own_.clear();
  held_.clear();
  linked_stepper_.Clear();
  std::size_t solved = 0;    // enabled bodies of this pass linked by a joint: QuickStep's work
  std::size_t on_field = 0;  // of those, static-contact islands (own_ takes them)
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    // Another pass's bodies are paused below, and only if QuickStep runs (most passes it does not).
    if (!InPass(i, pass)) continue;
    dBodyID b = bodies[i];
    if (!dBodyIsEnabled(b)) continue;
    const LoggedContact* kept = static_contacts_ ? static_contacts_->Kept(b) : nullptr;
    if (kept && IsStaticContactIsland(b, kept)) {
      own_.push_back({b, kept});
      ++on_field;
    } else if (!kept && IsLoneEnabledBody(b)) {  // enabled: looked at above
      own_.push_back({b, nullptr});
    } else if (!kept && static_contacts_ && InLinkedIsland(b)) {
      // Reached by the search of a linked island before it: stepped with that island.
    } else if (const int linked = !kept && static_contacts_ ? linked_stepper_.Gather(b, *static_contacts_) : -1;
               linked >= 0) {
      own_.push_back({b, nullptr, linked});
      ++on_field;
    } else {
      if (kept) static_contacts_->Join(b);  // QuickStep's: its contacts become ODE joints
      ++solved;
      if (IsLimb(i)) held_.push_back(b);  // a limb has a joint: never lone
    }
  }
  if (on_field > 0 && solved > 0 && iterations >= ContactIslandStepper::kFirstShuffle) {
    // QuickStep shuffles an island's rows with ODE's generator from its ninth sweep on, island
    // after island in its own order: the kernel's islands must draw between QuickStep's where
    // QuickStep would have stepped them.
    InterleavedPass(world, bodies, pass, iterations, dt);
    return;
  }
  if (move_order_matters_ && solved > 0 && !own_.empty()) {
    // QuickStep would have moved the kernel's bodies between its other islands: the broadphase
    // lists the geometries in the order they first moved, and that order decides which contact
    // comes first. Touching every body of the pass in QuickStep's order first keeps those lists
    // as they were; the moves that follow do not reorder what is listed already. The touch
    // costs about a tenth of what a lone body saves: for a ball in flight among a hundred wheel
    // bodies, QuickStep keeps it (the same numbers either way). A static-contact island saves
    // far more than the touch costs.
    if (on_field == 0 && own_.size() * 10 < solved) {
      own_.clear();
    } else {
      TouchInQuickStepOrder(bodies, pass);
    }
  }
  if (on_field > 0) settings_ = ContactSolverSettings::Of(world);
  for (const OwnIsland& o : own_) {
    StepOwn(o, iterations, dt);
    // Stepped: QuickStep must not step it again.
    if (o.linked >= 0) {
      paused_.insert(paused_.end(), linked_stepper_.BodiesBegin(o.linked), linked_stepper_.BodiesEnd(o.linked));
    } else {
      paused_.push_back(o.body);
    }
  }
  if (solved == 0) return;
  // The other passes' enabled bodies sit this QuickStep out.
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (!InPass(i, pass) && dBodyIsEnabled(bodies[i])) paused_.push_back(bodies[i]);
  }
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

void IslandStepper::StepOwn(const OwnIsland& o, int iterations, double dt) {
  if (o.contacts) {
    contact_stepper_.Step(o.body, *o.contacts, *static_contacts_, gravity_, settings_, iterations, dt);
  } else if (o.linked >= 0) {
    linked_stepper_.Step(o.linked, gravity_, settings_, iterations, dt);
    ++linked_islands_stepped_;
  } else {
    lone_stepper_.Step(o.body, gravity_, dt);
  }
}

bool IslandStepper::InLinkedIsland(dBodyID b) const {
  for (const OwnIsland& o : own_) {
    if (o.linked >= 0 && std::find(linked_stepper_.BodiesBegin(o.linked), linked_stepper_.BodiesEnd(o.linked), b) !=
                             linked_stepper_.BodiesEnd(o.linked)) {
      return true;
    }
  }
  return false;
}

void IslandStepper::InterleavedPass(dWorldID world, const std::vector<dBodyID>& bodies, int pass, int iterations,
                                    double dt) {
  // Every body the kernel steps is touched first in QuickStep's order, as in Pass.
  if (move_order_matters_) TouchInQuickStepOrder(bodies, pass);
  settings_ = ContactSolverSettings::Of(world);
  const auto own_island = [this](dBodyID b) -> const OwnIsland* {
    for (const OwnIsland& o : own_) {
      if (o.body == b) return &o;
    }
    return nullptr;
  };
  // Lone bodies draw nothing from the generator: stepped first.
  for (const OwnIsland& o : own_) {
    if (!o.contacts && o.linked < 0) lone_stepper_.Step(o.body, gravity_, dt);
  }
  // QuickStep's islands in its order (its search, as TouchInQuickStepOrder's), gathered into
  // one QuickStep call until a static-contact island comes, which the kernel steps between.
  segment_.clear();
  reached_.clear();
  const auto flush = [&] {
    if (segment_.empty()) return;
    const auto in_segment = [this](dBodyID b) {
      return std::find(segment_.begin(), segment_.end(), b) != segment_.end();
    };
    walk_.clear();  // the bodies this call leaves out
    for (dBodyID b : bodies) {
      if (dBodyIsEnabled(b) && !in_segment(b)) {
        dBodyDisable(b);
        walk_.push_back(b);
      }
    }
    for (dBodyID b : held_) {
      if (in_segment(b)) dBodyDisable(b);  // its root's search reaches it
    }
    dWorldSetQuickStepNumIterations(world, iterations);
    dWorldQuickStep(world, dt);
    for (dBodyID b : walk_) dBodyEnable(b);
    for (dBodyID b : held_) {
      if (!dBodyIsEnabled(b)) dBodyEnable(b);
    }
    walk_.clear();
    segment_.clear();
  };
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    dBodyID b = bodies[i];
    if (!dBodyIsEnabled(b) || !InPass(i, pass) || IsLimb(i)) continue;
    if (std::find(reached_.begin(), reached_.end(), b) != reached_.end()) continue;
    reached_.push_back(b);
    if (const OwnIsland* o = own_island(b)) {
      if (o->contacts || o->linked >= 0) {
        flush();
        StepOwn(*o, iterations, dt);
      }
      if (o->linked >= 0) {  // its other bodies come later in the list: passed
        reached_.insert(reached_.end(), linked_stepper_.BodiesBegin(o->linked), linked_stepper_.BodiesEnd(o->linked));
      }
      continue;
    }
    // A QuickStep island: every body its search reaches.
    const std::size_t first = segment_.size();
    segment_.push_back(b);
    for (std::size_t next = first; next < segment_.size(); ++next) {
      ForEachLinkedBody(segment_[next], [this](dBodyID other) {
        if (std::find(reached_.begin(), reached_.end(), other) == reached_.end()) {
          reached_.push_back(other);
          segment_.push_back(other);
        }
      });
    }
  }
  flush();
}

void IslandStepper::TouchInQuickStepOrder(const std::vector<dBodyID>& bodies, int pass) {
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
    if (!dBodyIsEnabled(b) || !InPass(i, pass) || IsLimb(i) || !reach(b)) continue;
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
