// SPDX-License-Identifier: Apache-2.0
#pragma once

// Helpers shared by the model-file sources (private to ubersim_model).

#include <string>

#include "ubersim/kernel/model.hpp"
#include "ubersim/params.hpp"

namespace ubersim::kernel::model_detail {

/// Shortest text that reads back as the same double ("0.0215", "1e-07").
std::string FormatNumber(double v);

/// What a value is, for messages: "string \"abc\"", "integer 3", "number 1.5", "bool true",
/// "null", "an array", "an object".
std::string Describe(const detail::ParamNode& n);

/// A ModelError at `where` (its file, line, column and key path).
ModelError ErrorAt(const ParamView& where, const std::string& reason);

/// A ModelError at `where`'s location, naming `key` instead of where's own path.
ModelError ErrorAt(const ParamView& where, const std::string& key, const std::string& reason);

/// "a.b" from "a" and "b"; "b" when the base is empty.
std::string JoinKey(const std::string& base, const std::string& key);

}  // namespace ubersim::kernel::model_detail
