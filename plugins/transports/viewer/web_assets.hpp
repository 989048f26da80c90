// SPDX-License-Identifier: Apache-2.0
// The page's files, built into the plugin (web_assets.cpp is generated from web/ at build time),
// so the viewer needs no internet and no install folder.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>

namespace ubersim::viewer {

/// One file of the page.
struct WebAsset {
  std::string_view path;          ///< URL path, e.g. "/viewer.js"
  std::string_view content_type;  ///< MIME type with charset
  std::string_view body;          ///< the bytes
};

/// Every file of web/, with "/index.html" among them.
std::span<const WebAsset> WebAssets();

/// The asset at `path` ("/" means "/index.html"), or nullptr.
const WebAsset* FindWebAsset(std::string_view path);

}  // namespace ubersim::viewer
