// SPDX-License-Identifier: Apache-2.0
// PluginRegistry: finds plugin libraries, checks them before running any of their code, and
// creates instances that keep their library loaded.
#include <dlfcn.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <exception>
#include <set>
#include <sstream>
#include <system_error>

#include <boost/dll/shared_library.hpp>

#include "ubersim/kernel/plugin_registry.hpp"

namespace ubersim::kernel {
namespace fs = std::filesystem;

PluginLoadError::PluginLoadError(std::string where, std::string reason, bool not_found)
    : std::runtime_error(where + ": " + reason),
      where_(std::move(where)),
      reason_(std::move(reason)),
      not_found_(not_found) {}

/// A loaded (or in-process) plugin: its descriptor, and the library that must outlive instances.
struct PluginRegistry::Entry {
  PluginInfo info;
  const PluginDescriptor* descriptor = nullptr;
  std::shared_ptr<boost::dll::shared_library> library;  // null for in-process plugins
};

namespace {

constexpr const char* kLibraryPrefix = "libubersim_";
constexpr const char* kLibrarySuffix = ".so";

bool ValidId(const char* id) {
  if (!id || !*id || !std::islower(static_cast<unsigned char>(*id))) return false;
  for (const char* c = id; *c; ++c) {
    if (!std::islower(static_cast<unsigned char>(*c)) && !std::isdigit(static_cast<unsigned char>(*c)) &&
        *c != '_') {
      return false;
    }
  }
  return true;
}

bool ValidKind(PluginKind k) {
  return k == PluginKind::kDrive || k == PluginKind::kDribbler || k == PluginKind::kKicker ||
         k == PluginKind::kTransport;
}

std::string AbiText(std::uint32_t word) {
  return "plugin ABI " + std::to_string(word >> 16) + " / SDK major " + std::to_string(word & 0xffff);
}

bool IsPluginFileName(const fs::path& p) {
  const std::string name = p.filename().string();
  return name.rfind(kLibraryPrefix, 0) == 0 && name.size() > 3 &&
         name.compare(name.size() - 3, 3, kLibrarySuffix) == 0;
}

// The dynamic loader's own words from Boost.DLL's message ("… (dlerror system message: X): …").
std::string LoaderMessage(const std::string& boost_message) {
  const std::string tag = "dlerror system message: ";
  const std::size_t start = boost_message.find(tag);
  if (start == std::string::npos) return boost_message;
  const std::size_t end = boost_message.rfind("):");
  const std::size_t from = start + tag.size();
  return boost_message.substr(from, end == std::string::npos || end < from ? std::string::npos : end - from);
}

// Checks a descriptor's fields; returns "" when acceptable, else the reason.
std::string CheckDescriptor(const PluginDescriptor& d) {
  if (d.abi_word != kPluginAbiWord) {
    return "descriptor built for " + AbiText(d.abi_word) + ", this kernel has " + AbiText(kPluginAbiWord);
  }
  if (d.descriptor_size != sizeof(PluginDescriptor)) {
    return "descriptor size " + std::to_string(d.descriptor_size) + " differs from the kernel's " +
           std::to_string(sizeof(PluginDescriptor));
  }
  if (!d.build_tag || std::string(d.build_tag) != kBuildTag) {
    return std::string("built with C++ library ABI '") + (d.build_tag ? d.build_tag : "?") +
           "', this kernel uses '" + kBuildTag + "'";
  }
  if (d.sdk_major != kSdkVersionMajor || d.sdk_minor > kSdkVersionMinor) {
    return "built against SDK " + std::to_string(d.sdk_major) + "." + std::to_string(d.sdk_minor) +
           ", this kernel provides SDK " + std::to_string(kSdkVersionMajor) + "." +
           std::to_string(kSdkVersionMinor);
  }
  if (!ValidKind(d.kind)) {
    return "unknown plugin kind " + std::to_string(static_cast<std::uint32_t>(d.kind));
  }
  if (!ValidId(d.id)) {
    return std::string("plugin id '") + (d.id ? d.id : "") + "' is not lower_snake_case";
  }
  if (!d.create || !d.destroy) return "descriptor has no create/destroy functions";
  return "";
}

}  // namespace

PluginRegistry::PluginRegistry(std::vector<fs::path> search_paths)
    : search_paths_(std::move(search_paths)) {}

PluginRegistry::~PluginRegistry() = default;

std::vector<fs::path> PluginRegistry::DefaultSearchPaths(const std::vector<fs::path>& world_paths) {
  std::vector<fs::path> candidates = world_paths;
  if (const char* env = std::getenv("UBERSIM_PLUGIN_PATH"); env && *env) {
    std::stringstream ss(env);
    std::string item;
    while (std::getline(ss, item, ':')) {
      if (!item.empty()) candidates.emplace_back(item);  // an empty entry must not mean "."
    }
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(exe.parent_path() / ".." / "lib" / "ubersim" / "plugins");
  candidates.push_back(fs::path(UBERSIM_INSTALL_PREFIX) / UBERSIM_PLUGIN_INSTALL_DIR);

  std::vector<fs::path> out;
  std::set<fs::path> seen;
  for (const fs::path& c : candidates) {
    if (c.empty() || c.is_relative()) {
      // Relative entries would depend on the current directory, which is never searched.
      if (c.empty()) continue;
    }
    const fs::path absolute = fs::absolute(c, ec);
    if (ec || !fs::is_directory(absolute, ec)) continue;
    const fs::path canonical = fs::canonical(absolute, ec);
    if (ec || !seen.insert(canonical).second) continue;
    out.push_back(canonical);
  }
  return out;
}

const PluginInfo& PluginRegistry::LoadFile(const fs::path& file) {
  std::error_code ec;
  const std::string where = file.string();
  if (!fs::exists(file, ec)) throw PluginLoadError(where, "no such file");
  if (!fs::is_regular_file(file, ec)) throw PluginLoadError(where, "not a regular file");
  const fs::path canonical = fs::canonical(file, ec);
  for (const auto& [id, e] : entries_) {
    if (e->library && e->info.file == canonical) return e->info;  // already loaded
  }

  auto library = std::make_shared<boost::dll::shared_library>();
  try {
    // rtld_now: a missing symbol fails here, not in the middle of a match; rtld_local: plugins
    // cannot see each other's symbols; RTLD_NODELETE: code of a plugin (a destructor, a thrown
    // exception's type) stays mapped even if something outlives its last holder. glibc hides
    // such bugs only by luck (STB_GNU_UNIQUE symbols), so make it explicit.
    library->load(canonical, boost::dll::load_mode::rtld_now | boost::dll::load_mode::rtld_local |
                                 static_cast<boost::dll::load_mode::type>(RTLD_NODELETE));
  } catch (const std::exception& e) {
    throw PluginLoadError(where, "cannot be loaded: " + LoaderMessage(e.what()));
  }
  if (!library->has(kAbiWordSymbol)) {
    throw PluginLoadError(where, std::string("not an ÜberSim plugin (no ") + kAbiWordSymbol + " symbol)");
  }
  // The ABI word is plain data: read it before calling anything in the library.
  const std::uint32_t abi_word = library->get_alias<const std::uint32_t>(kAbiWordSymbol);
  if (abi_word != kPluginAbiWord) {
    throw PluginLoadError(where, "built for " + AbiText(abi_word) + ", this kernel has " +
                                     AbiText(kPluginAbiWord));
  }
  if (!library->has(kDescriptorSymbol)) {
    throw PluginLoadError(where, std::string("has ") + kAbiWordSymbol + " but no " + kDescriptorSymbol);
  }
  const PluginDescriptor* descriptor = nullptr;
  try {
    descriptor = library->get_alias<const PluginDescriptor*()>(kDescriptorSymbol)();
  } catch (const std::exception& e) {
    throw PluginLoadError(where, std::string("descriptor function threw: ") + e.what());
  } catch (...) {
    throw PluginLoadError(where, "descriptor function threw a non-standard exception");
  }
  if (!descriptor) throw PluginLoadError(where, "descriptor function returned null");
  if (const std::string why = CheckDescriptor(*descriptor); !why.empty()) {
    throw PluginLoadError(where, why);
  }
  const std::string id = descriptor->id;
  if (const auto it = entries_.find(id); it != entries_.end()) {
    throw PluginLoadError(where, "duplicate plugin id '" + id + "': already loaded from " +
                                     it->second->info.file.string());
  }
  auto entry = std::make_shared<Entry>();
  entry->descriptor = descriptor;
  entry->library = std::move(library);
  entry->info = PluginInfo{id,
                           descriptor->kind,
                           descriptor->version ? descriptor->version : "",
                           std::to_string(descriptor->sdk_major) + "." + std::to_string(descriptor->sdk_minor),
                           canonical,
                           descriptor->schema_json ? descriptor->schema_json : ""};
  return entries_.emplace(id, std::move(entry)).first->second->info;
}

void PluginRegistry::Add(const PluginDescriptor& descriptor) {
  if (const std::string why = CheckDescriptor(descriptor); !why.empty()) {
    throw PluginLoadError("<in-process>", why);
  }
  const std::string id = descriptor.id;
  if (const auto it = entries_.find(id); it != entries_.end()) {
    throw PluginLoadError("<in-process>", "duplicate plugin id '" + id + "': already loaded from " +
                                              it->second->info.file.string());
  }
  auto entry = std::make_shared<Entry>();
  entry->descriptor = &descriptor;
  entry->info = PluginInfo{id,
                           descriptor.kind,
                           descriptor.version ? descriptor.version : "",
                           std::to_string(descriptor.sdk_major) + "." + std::to_string(descriptor.sdk_minor),
                           "<in-process>",
                           descriptor.schema_json ? descriptor.schema_json : ""};
  entries_.emplace(id, std::move(entry));
}

PluginRegistry::ScanResult PluginRegistry::Scan() {
  ScanResult result;
  std::set<std::string> listed;
  for (const fs::path& dir : search_paths_) {
    std::error_code ec;
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      if (IsPluginFileName(entry.path())) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());  // directory order is not stable
    for (const fs::path& f : files) {
      try {
        const PluginInfo& info = LoadFile(f);
        // Find looks plugins up by file name: a file named for another id is not what a world
        // naming either id would use, so it is listed as a problem, not as a plugin.
        const std::string name = f.filename().string();
        const std::string named_for = name.substr(std::string(kLibraryPrefix).size(),
                                                  name.size() - std::string(kLibraryPrefix).size() - 3);
        if (named_for != info.id) {
          result.problems.push_back(f.string() + ": file is named for '" + named_for + "' but its descriptor says '" +
                                    info.id + "' (a world naming either would not get it)");
          continue;
        }
        if (listed.insert(info.id).second) result.plugins.push_back(info);
      } catch (const PluginLoadError& e) {
        result.problems.push_back(e.what());
      }
    }
  }
  return result;
}

const PluginInfo& PluginRegistry::Find(PluginKind kind, const std::string& id) {
  auto check_kind = [&](const PluginInfo& info) -> const PluginInfo& {
    if (info.kind != kind) {
      throw PluginLoadError(info.file.string(), "'" + id + "' is a " + ToString(info.kind) +
                                                    " plugin, not a " + ToString(kind));
    }
    return info;
  };
  if (const auto it = entries_.find(id); it != entries_.end()) return check_kind(it->second->info);

  const std::string file_name = kLibraryPrefix + id + kLibrarySuffix;
  std::string searched;
  std::vector<std::string> refused;  // files of that name that could not be used, and why
  for (const fs::path& dir : search_paths_) {
    const fs::path candidate = dir / file_name;
    std::error_code ec;
    if (fs::exists(candidate, ec)) {
      const PluginInfo* info = nullptr;
      try {
        info = &LoadFile(candidate);
        if (info->id != id) {
          throw PluginLoadError(candidate.string(), "file is named for '" + id + "' but its descriptor says '" +
                                                        info->id + "'");
        }
      } catch (const PluginLoadError& e) {
        refused.push_back(e.what());  // keep looking: a stale library must not hide a good one
        continue;
      }
      // The id is taken now: another kind under that id is an error of the model, not the file.
      const PluginInfo& good = check_kind(*info);
      for (const std::string& r : refused) skipped_.push_back(r + " (skipped: using " + good.file.string() + ")");
      return good;
    }
    std::string found;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      const std::string name = entry.path().filename().string();
      if (IsPluginFileName(entry.path())) {
        found += (found.empty() ? "" : ", ") +
                 name.substr(std::string(kLibraryPrefix).size(),
                             name.size() - std::string(kLibraryPrefix).size() - 3);
      }
    }
    searched += (searched.empty() ? "" : "; ") + dir.string() +
                (found.empty() ? " (nothing)" : " (found: " + found + ")");
  }
  if (!refused.empty()) {
    std::string reasons;
    for (const std::string& r : refused) reasons += (reasons.empty() ? "" : "; ") + r;
    throw PluginLoadError("plugin '" + id + "' (" + ToString(kind) + ")",
                          "refused: " + reasons + (searched.empty() ? "" : "; no other found in " + searched));
  }
  throw PluginLoadError("plugin '" + id + "' (" + ToString(kind) + ")",
                        "not found; searched " + (searched.empty() ? std::string("no folders") : searched) +
                            "; set UBERSIM_PLUGIN_PATH or plugin_paths in the world file",
                        /*not_found=*/true);
}

std::shared_ptr<void> PluginRegistry::Create(PluginKind kind, const std::string& id) {
  Find(kind, id);
  const std::shared_ptr<Entry> entry = entries_.at(id);
  void* raw = nullptr;
  try {
    raw = entry->descriptor->create();
  } catch (const std::exception& e) {
    throw PluginLoadError(entry->info.file.string(), "plugin '" + id + "': constructor threw: " + e.what());
  } catch (...) {
    throw PluginLoadError(entry->info.file.string(),
                          "plugin '" + id + "': constructor threw a non-standard exception");
  }
  if (!raw) throw PluginLoadError(entry->info.file.string(), "plugin '" + id + "': create returned null");
  // The deleter holds the entry, and so the library, until the instance is gone.
  return std::shared_ptr<void>(raw, [entry](void* p) { entry->descriptor->destroy(p); });
}

std::shared_ptr<Drive> PluginRegistry::CreateDrive(const std::string& id) {
  auto p = Create(PluginKind::kDrive, id);
  return std::shared_ptr<Drive>(p, static_cast<Drive*>(p.get()));
}

std::shared_ptr<Dribbler> PluginRegistry::CreateDribbler(const std::string& id) {
  auto p = Create(PluginKind::kDribbler, id);
  return std::shared_ptr<Dribbler>(p, static_cast<Dribbler*>(p.get()));
}

std::shared_ptr<Kicker> PluginRegistry::CreateKicker(const std::string& id) {
  auto p = Create(PluginKind::kKicker, id);
  return std::shared_ptr<Kicker>(p, static_cast<Kicker*>(p.get()));
}

std::shared_ptr<Transport> PluginRegistry::CreateTransport(const std::string& id) {
  auto p = Create(PluginKind::kTransport, id);
  return std::shared_ptr<Transport>(p, static_cast<Transport*>(p.get()));
}

}  // namespace ubersim::kernel
