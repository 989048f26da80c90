// SPDX-License-Identifier: Apache-2.0
// The plugin registry: where plugin libraries are searched for, the listing of what was found
// (accepted plugins and refused files with the reason), and instances created from them.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "ubersim/plugin_descriptor.hpp"

namespace ubersim::kernel {

/// A plugin the registry accepted.
struct PluginInfo {
  std::string id;                 ///< plugin id ("omni")
  PluginKind kind;                ///< what it provides
  std::string version;            ///< the plugin's own version
  std::string sdk_version;        ///< "major.minor" it was built against
  std::filesystem::path file;     ///< library file ("<static>" for in-process registrations)
  std::string schema_json;        ///< JSON Schema of its parameter block
};

/// A plugin that could not be found, loaded or created: names the file (or the paths searched)
/// and the reason.
class PluginLoadError : public std::runtime_error {
 public:
  /// `where` is the library path or the id asked for; `reason` says why. `not_found`: no library
  /// of that id is anywhere in the search path (as opposed to one found and refused).
  PluginLoadError(std::string where, std::string reason, bool not_found = false);
  const std::string& where() const { return where_; }    ///< file or id
  const std::string& reason() const { return reason_; }  ///< why
  bool not_found() const { return not_found_; }          ///< nothing of that id was found at all
 private:
  std::string where_;
  std::string reason_;
  bool not_found_ = false;
};

/// Finds, loads and checks plugin libraries (Boost.DLL), and creates plugin instances that keep
/// their library loaded while they live. Load everything on the main thread.
class PluginRegistry {
 public:
  /// Searches `search_paths` in order (see DefaultSearchPaths).
  explicit PluginRegistry(std::vector<std::filesystem::path> search_paths);
  ~PluginRegistry();
  PluginRegistry(const PluginRegistry&) = delete;
  PluginRegistry& operator=(const PluginRegistry&) = delete;

  /// The search order: `world_paths` (from the world file), then each entry of
  /// $UBERSIM_PLUGIN_PATH (colon-separated), then the plugins built beside the running
  /// executable (../lib/ubersim/plugins), then <install prefix>/lib/ubersim/plugins.
  /// Never the current directory.
  static std::vector<std::filesystem::path> DefaultSearchPaths(
      const std::vector<std::filesystem::path>& world_paths = {});

  /// The folders searched, in order.
  const std::vector<std::filesystem::path>& SearchPaths() const { return search_paths_; }

  /// Every plugin library in the search paths (libubersim_*.so): accepted ones, and a message
  /// per refused file ("<path>: <reason>").
  struct ScanResult {
    std::vector<PluginInfo> plugins;     ///< accepted, in search order
    std::vector<std::string> problems;   ///< refused files and why
  };
  /// Loads every library it finds (first one wins for a duplicated id; later ones are problems).
  ScanResult Scan();

  /// Loads one library file and checks it (ABI word, descriptor size, build tag, SDK version,
  /// kind, duplicate id); throws PluginLoadError naming the file and the reason.
  const PluginInfo& LoadFile(const std::filesystem::path& file);

  /// Finds plugin `id` of `kind`: already loaded, else the first libubersim_<id>.so in the search
  /// paths that loads and is of that id and kind. A refused file earlier in the path does not hide
  /// a good one later: it is skipped, and said so in Skipped(). Throws PluginLoadError naming every
  /// refused file and why, or (not_found) every path tried and the ids found there.
  const PluginInfo& Find(PluginKind kind, const std::string& id);
  /// Files Find passed over on its way to a good one, as "<file>: <reason>", in the order met.
  const std::vector<std::string>& Skipped() const { return skipped_; }

  /// Registers an in-process plugin (tests, built-ins); throws PluginLoadError on a duplicate id.
  void Add(const PluginDescriptor& descriptor);

  /// Creates an instance of plugin `id`; the library stays loaded while it lives. A throwing
  /// constructor becomes PluginLoadError naming the file and the exception.
  std::shared_ptr<Drive> CreateDrive(const std::string& id);
  std::shared_ptr<Dribbler> CreateDribbler(const std::string& id);   ///< as CreateDrive
  std::shared_ptr<Kicker> CreateKicker(const std::string& id);       ///< as CreateDrive
  std::shared_ptr<Transport> CreateTransport(const std::string& id); ///< as CreateDrive

 private:
  struct Entry;
  std::shared_ptr<void> Create(PluginKind kind, const std::string& id);
  std::vector<std::filesystem::path> search_paths_;
  std::map<std::string, std::shared_ptr<Entry>> entries_;  // by id
  std::vector<std::string> skipped_;
};

}  // namespace ubersim::kernel
