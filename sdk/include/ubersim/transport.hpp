// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ubersim/events.hpp"
#include "ubersim/export.hpp"
#include "ubersim/log.hpp"
#include "ubersim/params.hpp"
#include "ubersim/world_state.hpp"

namespace ubersim {
inline namespace v1 {

/// What the kernel gives a transport.
class UBERSIM_SDK_API TransportContext {
 public:
  virtual ~TransportContext();
  /// The transport's own parameter block, already validated.
  virtual const ParamView& Params() const = 0;
  /// A log that prefixes the transport's name.
  virtual Log& Logger() = 0;
  /// Where to post position, command, query and clock events (thread-safe).
  virtual EventSink& Events() = 0;
  /// The world's field geometry.
  virtual const FieldGeometry& Field() const = 0;
  /// The world's name.
  virtual const std::string& WorldName() const = 0;
  /// The simulated cameras (ids and positions), for geometry packets.
  virtual std::vector<CameraInfo> Cameras() const = 0;
  /// True when the world keeps every transport on loopback (the world's `local_only: true`,
  /// `ubersim run --local-only`): no socket bound or sent on another interface.
  virtual bool LocalOnly() const = 0;
};

/// Connects the simulation to the outside (network protocols, viewers). Poll, Publish and
/// OnVisionFrame run on the simulation thread; a transport's own threads talk to the kernel only
/// through EventSink, and Stop joins them.
class UBERSIM_SDK_API Transport {
 public:
  virtual ~Transport();
  /// Opens sockets and starts threads; throw PluginError when that fails.
  virtual void Start(TransportContext& context) = 0;
  /// At the start of each step, on the simulation thread.
  virtual void Poll() {}
  /// After each step with the ground truth, and once before the first step and after a reset
  /// (same step number, no stepping); must be cheap (copy what you need and return).
  virtual void Publish(const WorldSnapshot& /*snapshot*/) {}
  /// When a camera frame leaves the perception pipeline's latency queue.
  virtual void OnVisionFrame(const VisionFrame& /*frame*/) {}
  /// A setting changed while running (TransportSettingEvent, e.g. "vision_port"), on the
  /// simulation thread: true when this transport took it; throw PluginError for a value it
  /// refuses (the message is the answer).
  virtual bool OnSetting(const std::string& /*name*/, std::int64_t /*value*/) { return false; }
  /// Where it listens or sends, for `ubersim run` to print ("udp 224.5.23.2:10020").
  virtual std::string Endpoint() const { return {}; }
  /// Closes sockets and joins every thread it started.
  virtual void Stop() = 0;
};

}  // namespace v1
}  // namespace ubersim
