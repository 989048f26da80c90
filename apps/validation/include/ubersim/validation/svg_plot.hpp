// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <string>

#include "ubersim/validation/result.hpp"

namespace ubersim::validation {

/// Renders a plot as a self-contained SVG document (axes with rounded ticks, a legend).
std::string RenderSvg(const Plot& plot);

}  // namespace ubersim::validation
