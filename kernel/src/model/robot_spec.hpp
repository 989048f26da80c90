// SPDX-License-Identifier: Apache-2.0
// Where each field of a RobotSpec goes in a robot model file: the body block's keys, and the
// plugin parameters whose schema names the field (`"robot_spec": "max_speed"`, with
// `"robot_spec_scale"` for a key in other units, e.g. degrees). Private to ubersim_model.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ubersim/detail/param_node.hpp"
#include "ubersim/events.hpp"

namespace ubersim::kernel::model_detail {

/// One value a spec writes into a robot file's tree.
struct SpecEdit {
  std::string field;               ///< the RobotSpec field, e.g. "max_speed"
  std::vector<std::string> path;   ///< keys from the file's root, e.g. {"drive", "limits", "max_speed"}
  std::optional<std::size_t> item;  ///< for an array of objects: the element (path ends at the array,
                                    ///< `member` names the key inside the element)
  std::string member;              ///< see `item`
  double value = 0;                ///< in the key's units
};

/// A spec field's place in one plugin's parameter block, from the plugin's schema.
struct SpecTarget {
  std::string field;              ///< RobotSpec field
  std::vector<std::string> path;  ///< keys inside the block; for an array field, the array
  std::string member;             ///< for an array of objects: the key inside each element
  double scale = 1.0;             ///< key units per SI unit
};

/// Every `robot_spec` annotation of a plugin's schema (draft-04 JSON text); empty when none or
/// the text is not JSON.
std::vector<SpecTarget> SpecTargets(const std::string& schema_json);

/// The names of the RobotSpec fields that are set, in declaration order.
std::vector<std::string> SetFields(const RobotSpec& spec);

/// The value of a set scalar field (nullopt for wheel_angles or an unset one).
std::optional<double> ScalarField(const RobotSpec& spec, const std::string& field);

/// A copy of `root` with `edit` applied: objects on the way are made when missing; the edited
/// value is located as `source` (so errors name the spec, not the file's line).
detail::ParamNode WithEdit(const detail::ParamNode& root, const SpecEdit& edit, const std::string& source);

/// "radius 0.3 m", for messages.
std::string DescribeField(const RobotSpec& spec, const std::string& field);

/// A digest of the set fields and their values (bit for bit).
std::uint64_t SpecDigest(const RobotSpec& spec);

}  // namespace ubersim::kernel::model_detail
