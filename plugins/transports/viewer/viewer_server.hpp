// SPDX-License-Identifier: Apache-2.0
// The viewer's HTTP + WebSocket server (Boost.Beast), on one thread of its own.
//
// HTTP GET serves the page's built-in files and /api/state (the latest state message); a
// WebSocket at /ws gets the hello message, then state (and referee) messages. A browser that
// reads slowly only ever has the newest message of each channel waiting for it (older ones are
// replaced, never queued), so neither memory nor the simulation thread pays for a slow or
// vanished client, and a state message never pushes out a referee message that is still waiting.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <ubersim/log.hpp>

namespace ubersim::viewer {

/// Listens on one TCP port for browsers.
class ViewerServer {
 public:
  /// Where and how many.
  struct Options {
    std::string address = "127.0.0.1";  ///< numeric address to listen on
    std::uint16_t port = 8080;          ///< 0: the system picks a free port
    int max_clients = 16;               ///< WebSocket clients at once
    std::size_t max_message = 64 * 1024;  ///< longest message a page may send, bytes
    /// What the error of a port that cannot be had suggests, in parentheses.
    std::string busy_hint = "set another port in the world file's viewer block, or run with --no-viewer";
  };
  /// What the server asks its owner; all called on the server's thread.
  struct Callbacks {
    std::function<std::string()> hello;                         ///< first message to a new client
    std::function<std::vector<std::string>()> catch_up;         ///< then these (may be unset or empty)
    std::function<std::string(std::string_view)> on_message;    ///< a page's message → reply ("" for none)
    std::function<std::string()> latest_state;                  ///< body of GET /api/state
    std::function<void()> tick;                                 ///< called every tick period
  };

  /// Binds and listens; throws std::runtime_error naming the address and the reason.
  ViewerServer(const Options& options, Callbacks callbacks, std::chrono::nanoseconds tick_period,
               Log& log);
  /// Stops and joins.
  ~ViewerServer();
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  /// Starts the server thread.
  void Start();
  /// Kinds of broadcast messages: each browser holds at most one waiting per channel, and they
  /// are written in this order (after the replies to its commands).
  enum class Channel { kHello, kReferee, kState };
  static constexpr int kChannels = 3;

  /// Hands every client this message (any thread; replaces the one of its channel still waiting).
  void Broadcast(std::shared_ptr<const std::string> message, Channel channel = Channel::kState);
  /// Connected WebSocket clients.
  int Clients() const;
  /// The port it listens on (the chosen one when Options::port was 0).
  std::uint16_t Port() const;
  /// "http://ADDRESS:PORT/".
  std::string Url() const;
  /// Closes every connection and joins the thread; idempotent.
  void Stop();

  /// The server's state (defined in viewer_server.cpp).
  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
  std::thread thread_;
};

}  // namespace ubersim::viewer
