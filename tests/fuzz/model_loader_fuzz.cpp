// SPDX-License-Identifier: Apache-2.0
// Fuzz target: the text of one model file (world, field, ball or robot), loaded and validated as
// `ubersim validate` does: YAML, the kind's JSON schema, the checks that span keys, the files it
// names, and each plugin block against the schema its plugin ships (the plugins built in this
// tree, loaded once through the real registry). The only failure allowed is a ModelError that
// says where.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "fuzz_checks.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"

namespace {

namespace fs = std::filesystem;
using ubersim::kernel::ModelLoader;
using ubersim::kernel::PluginRegistry;

const fs::path kSource = UBERSIM_SOURCE_DIR;
// Where the text pretends to live: beside the shipped robots, so the relative paths of the
// shipped files resolve ("urdf/…" of a robot, "../fields/…" of a world).
const fs::path kFile = kSource / "models" / "robots" / "fuzz-input.yaml";

const ModelLoader& Loader() {
  static PluginRegistry registry({fs::path(UBERSIM_PLUGIN_BUILD_DIR)});
  static const ModelLoader loader(kSource / "schemas", [](ubersim::PluginKind kind, const std::string& id) {
    return registry.Find(kind, id).schema_json;
  });
  return loader;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    Loader().ValidateText(text, kFile);
  } catch (const ubersim::kernel::ModelError& e) {
    ubersim::fuzz::Check(!e.file().empty() && !e.reason().empty(), "a model error that does not say where or why");
  }
  return 0;
}
