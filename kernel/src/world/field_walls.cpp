// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/field.hpp"

#include "world/world_attorney.hpp"

namespace ubersim::kernel {

std::vector<FieldWall> FieldWalls(const World& world) {
  std::vector<FieldWall> out;
  const NodeImpl* field = WorldAttorney::Scene(world).Root().FindChildNode("field");
  if (!field) return out;
  for (const auto& g : field->geoms()) {
    const Shape& s = g->GetShape();
    if (g->body() || s.kind != Shape::Kind::kBox) continue;
    out.push_back({g->Name(), g->GetPose(), s.size});
  }
  return out;
}

}  // namespace ubersim::kernel
