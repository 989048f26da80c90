// SPDX-License-Identifier: Apache-2.0
// A page's WebSocket to the viewer, blocking with a timeout, for the viewer's tests (the live
// world's in viewer_test.cpp, a replayed log's in viewer_replay_test.cpp).
#pragma once

#include <sys/socket.h>
#include <sys/time.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>  // before Boost.Asio: its 1.74 headers use std::exchange without it

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <gtest/gtest.h>
#include <rapidjson/document.h>

namespace ubersim::testing {

inline rapidjson::Document ParseJson(const std::string& text) {
  rapidjson::Document d;
  d.Parse(text.c_str());
  EXPECT_FALSE(d.HasParseError()) << text;
  return d;
}

// Every blocking read gives up after this long, so a broken server fails a test instead of
// hanging it.
inline void ReceiveTimeout(boost::asio::ip::tcp::socket& s, int seconds) {
  timeval tv{seconds, 0};
  setsockopt(s.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
}

/// A page's WebSocket on 127.0.0.1:port/ws.
struct WsClient {
  boost::asio::io_context io;
  boost::beast::websocket::stream<boost::asio::ip::tcp::socket> ws{io};

  explicit WsClient(std::uint16_t port) {
    ws.next_layer().connect(
        boost::asio::ip::tcp::endpoint(boost::asio::ip::make_address("127.0.0.1"), port));
    ReceiveTimeout(ws.next_layer(), 10);
    ws.handshake("127.0.0.1:" + std::to_string(port), "/ws");
  }
  std::string Read() {
    boost::beast::flat_buffer b;
    ws.read(b);
    return boost::beast::buffers_to_string(b.data());
  }
  // Reads until a message whose "type" is `type`, at most `limit` messages.
  std::optional<rapidjson::Document> TryReadType(const std::string& type, int limit) {
    for (int i = 0; i < limit; ++i) {
      rapidjson::Document d = ParseJson(Read());
      if (d.IsObject() && d.HasMember("type") && type == d["type"].GetString()) return d;
    }
    return std::nullopt;
  }
  rapidjson::Document ReadType(const std::string& type) {
    if (auto d = TryReadType(type, 1000)) return std::move(*d);
    ADD_FAILURE() << "no '" << type << "' message in 1000";
    return {};
  }
  void Send(const std::string& text) {
    ws.text(true);
    ws.write(boost::asio::buffer(text));
  }
};

}  // namespace ubersim::testing
