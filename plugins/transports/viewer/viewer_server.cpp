// SPDX-License-Identifier: Apache-2.0
#include "viewer_server.hpp"

#include <algorithm>
#include <array>
#include <deque>
#include <utility>
#include <optional>
#include <set>
#include <stdexcept>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "web_assets.hpp"

namespace ubersim::viewer {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Request = http::request<http::string_body>;
using Response = http::response<http::string_body>;

constexpr auto kHttpTimeout = std::chrono::seconds(30);
constexpr std::size_t kMaxRepliesWaiting = 64;  // a page that sends and never reads is cut off
constexpr const char* kServerName = "ubersim-viewer";

class WsSession;

}  // namespace

struct ViewerServer::Impl {
  Impl(const Options& o, Callbacks cb, std::chrono::nanoseconds tick, Log& l)
      : options(o), callbacks(std::move(cb)), tick_period(tick), log(l),
        acceptor(io), tick_timer(io), retry_timer(io) {}

  void Accept();
  void Tick();
  void CloseAll();

  Options options;
  Callbacks callbacks;
  std::chrono::nanoseconds tick_period;
  Log& log;
  std::atomic<int> clients{0};
  std::uint16_t port = 0;
  // Server thread only. Declared before io, so sessions destroyed with io's handlers still find it.
  std::set<WsSession*> sessions;
  bool stopping = false;
  asio::io_context io;
  tcp::acceptor acceptor;
  asio::steady_timer tick_timer;
  asio::steady_timer retry_timer;
};

namespace {

// One browser's WebSocket. Replies to its commands wait in order; of the state messages only the
// newest waits.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket socket, ViewerServer::Impl& server)
      : ws_(std::move(socket)), server_(server) {}
  ~WsSession() { Unregister(); }

  void Run(Request request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& res) { res.set(http::field::server, kServerName); }));
    ws_.read_message_max(server_.options.max_message);
    ws_.text(true);
    ws_.async_accept(request, beast::bind_front_handler(&WsSession::OnAccept, shared_from_this()));
  }

  void SetLatest(std::shared_ptr<const std::string> message, ViewerServer::Channel channel) {
    latest_[static_cast<int>(channel)] = std::move(message);
    Write();
  }

  void Close() {
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().close(ec);
  }

 private:
  void OnAccept(beast::error_code ec) {
    if (ec || server_.stopping) return;
    server_.sessions.insert(this);
    server_.clients.fetch_add(1);
    registered_ = true;
    Queue(server_.callbacks.hello());
    if (server_.callbacks.catch_up) {
      for (std::string& m : server_.callbacks.catch_up()) Queue(std::move(m));
    }
    Read();
  }

  void Unregister() {
    if (!registered_) return;
    registered_ = false;
    server_.sessions.erase(this);
    server_.clients.fetch_sub(1);
  }

  void Read() {
    ws_.async_read(in_, beast::bind_front_handler(&WsSession::OnRead, shared_from_this()));
  }

  void OnRead(beast::error_code ec, std::size_t) {
    if (ec) {
      // Closed, timed out, or a message over the size limit: the session ends.
      if (ec != websocket::error::closed && ec != asio::error::operation_aborted) {
        server_.log.Debug("viewer: client closed: " + ec.message());
      }
      Unregister();
      return;
    }
    std::string text = beast::buffers_to_string(in_.data());
    in_.consume(in_.size());
    std::string reply = ws_.got_text()
        ? server_.callbacks.on_message(text)
        : std::string(R"({"type":"error","cmd":"","message":"binary messages are not understood; send JSON text"})");
    if (!reply.empty() && !Queue(std::move(reply))) return;
    Read();
  }

  // Returns false (and closes) when the page does not read its replies.
  bool Queue(std::string message) {
    if (replies_.size() >= kMaxRepliesWaiting) {
      server_.log.Warning("viewer: a client sends commands but does not read the replies; closed");
      Unregister();
      Close();
      return false;
    }
    replies_.push_back(std::make_shared<const std::string>(std::move(message)));
    Write();
    return true;
  }

  void Write() {
    if (writing_) return;
    if (!replies_.empty()) {
      current_ = std::move(replies_.front());
      replies_.pop_front();
    } else {
      auto waiting = std::find_if(latest_.begin(), latest_.end(), [](const auto& m) { return m != nullptr; });
      if (waiting == latest_.end()) return;
      current_ = std::move(*waiting);
      waiting->reset();
    }
    writing_ = true;
    ws_.async_write(asio::buffer(*current_),
                    beast::bind_front_handler(&WsSession::OnWrite, shared_from_this()));
  }

  void OnWrite(beast::error_code ec, std::size_t) {
    writing_ = false;
    current_.reset();
    if (ec) {
      Unregister();
      return;
    }
    Write();
  }

  websocket::stream<beast::tcp_stream> ws_;
  ViewerServer::Impl& server_;
  beast::flat_buffer in_;
  std::deque<std::shared_ptr<const std::string>> replies_;
  std::array<std::shared_ptr<const std::string>, ViewerServer::kChannels> latest_;  // by channel
  std::shared_ptr<const std::string> current_;
  bool writing_ = false;
  bool registered_ = false;
};

Response MakeResponse(const Request& req, http::status status, std::string_view type,
                      std::string body) {
  Response res{status, req.version()};
  res.set(http::field::server, kServerName);
  res.set(http::field::content_type, beast::string_view(type.data(), type.size()));
  // The page is served by the simulator it shows; never let a browser mix versions.
  res.set(http::field::cache_control, "no-store");
  res.set("X-Content-Type-Options", "nosniff");
  res.keep_alive(req.keep_alive());
  if (req.method() == http::verb::head) {
    res.content_length(body.size());
  } else {
    res.body() = std::move(body);
    res.prepare_payload();
  }
  return res;
}

Response PlainError(const Request& req, http::status status, std::string text) {
  return MakeResponse(req, status, "text/plain; charset=utf-8", std::move(text) + "\n");
}

// One HTTP connection: files, /api/state, or the upgrade to a WebSocket.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, ViewerServer::Impl& server)
      : stream_(std::move(socket)), server_(server) {}

  void Run() { Read(); }

 private:
  void Read() {
    parser_.emplace();
    parser_->header_limit(16 * 1024);
    parser_->body_limit(16 * 1024);
    stream_.expires_after(kHttpTimeout);
    http::async_read(stream_, buffer_, *parser_,
                     beast::bind_front_handler(&HttpSession::OnRead, shared_from_this()));
  }

  void OnRead(beast::error_code ec, std::size_t) {
    if (ec == http::error::end_of_stream) {
      stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
      return;
    }
    if (ec || server_.stopping) return;
    Request req = parser_->release();
    if (websocket::is_upgrade(req)) {
      if (req.target() != "/ws") {
        Respond(PlainError(req, http::status::not_found, "the viewer's WebSocket is at /ws"));
        return;
      }
      if (server_.clients.load() >= server_.options.max_clients) {
        Respond(PlainError(req, http::status::service_unavailable,
                           "too many viewers connected (max_clients " +
                               std::to_string(server_.options.max_clients) + ")"));
        return;
      }
      stream_.expires_never();
      std::make_shared<WsSession>(stream_.release_socket(), server_)->Run(std::move(req));
      return;
    }
    Respond(Handle(req));
  }

  Response Handle(const Request& req) {
    if (req.method() != http::verb::get && req.method() != http::verb::head) {
      Response res = PlainError(req, http::status::method_not_allowed, "only GET and HEAD");
      res.set(http::field::allow, "GET, HEAD");
      return res;
    }
    std::string_view path(req.target().data(), req.target().size());
    path = path.substr(0, path.find('?'));
    if (path == "/api/state") {
      std::string state = server_.callbacks.latest_state();
      if (state.empty()) {
        return PlainError(req, http::status::service_unavailable, "no state yet: the world has not stepped");
      }
      return MakeResponse(req, http::status::ok, "application/json", std::move(state));
    }
    if (path == "/api/hello") {
      return MakeResponse(req, http::status::ok, "application/json", server_.callbacks.hello());
    }
    if (const WebAsset* asset = FindWebAsset(path)) {
      return MakeResponse(req, http::status::ok, asset->content_type, std::string(asset->body));
    }
    return PlainError(req, http::status::not_found, "not found: " + std::string(path));
  }

  void Respond(Response res) {
    auto message = std::make_shared<Response>(std::move(res));
    http::async_write(stream_, *message,
                      [self = shared_from_this(), message](beast::error_code ec, std::size_t) {
                        if (ec) return;
                        if (message->need_eof()) {
                          self->stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
                          return;
                        }
                        self->Read();
                      });
  }

  beast::tcp_stream stream_;
  ViewerServer::Impl& server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

}  // namespace

void ViewerServer::Impl::Accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (stopping || !acceptor.is_open()) return;
    if (ec) {
      // Out of file descriptors and the like: try again shortly instead of spinning.
      log.Warning("viewer: accepting a connection failed: " + ec.message());
      retry_timer.expires_after(std::chrono::milliseconds(100));
      retry_timer.async_wait([this](beast::error_code e) {
        if (!e) Accept();
      });
      return;
    }
    std::make_shared<HttpSession>(std::move(socket), *this)->Run();
    Accept();
  });
}

void ViewerServer::Impl::Tick() {
  tick_timer.expires_after(tick_period);
  tick_timer.async_wait([this](beast::error_code ec) {
    if (ec || stopping) return;
    if (callbacks.tick) callbacks.tick();
    Tick();
  });
}

void ViewerServer::Impl::CloseAll() {
  stopping = true;
  beast::error_code ec;
  acceptor.close(ec);
  tick_timer.cancel();
  retry_timer.cancel();
  for (WsSession* s : sessions) s->Close();
}

ViewerServer::ViewerServer(const Options& options, Callbacks callbacks,
                           std::chrono::nanoseconds tick_period, Log& log)
    : impl_(std::make_unique<Impl>(options, std::move(callbacks), tick_period, log)) {
  const std::string where = options.address + ":" + std::to_string(options.port);
  beast::error_code ec;
  const auto address = asio::ip::make_address(options.address, ec);
  if (ec) throw std::runtime_error("viewer: '" + options.address + "' is not a numeric IP address");
  const tcp::endpoint endpoint(address, options.port);
  tcp::acceptor& a = impl_->acceptor;
  a.open(endpoint.protocol(), ec);
  if (!ec) a.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(endpoint, ec);
  if (!ec) a.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    throw std::runtime_error("viewer: cannot listen on " + where + ": " + ec.message() +
                             (options.busy_hint.empty() ? std::string() : " (" + options.busy_hint + ")"));
  }
  impl_->port = a.local_endpoint().port();
}

ViewerServer::~ViewerServer() { Stop(); }

void ViewerServer::Start() {
  if (thread_.joinable()) return;
  impl_->Accept();
  impl_->Tick();
  thread_ = std::thread([impl = impl_.get()] { impl->io.run(); });
}

void ViewerServer::Broadcast(std::shared_ptr<const std::string> message, Channel channel) {
  asio::post(impl_->io, [impl = impl_.get(), message = std::move(message), channel] {
    for (WsSession* s : impl->sessions) s->SetLatest(message, channel);
  });
}

int ViewerServer::Clients() const { return impl_->clients.load(); }

std::uint16_t ViewerServer::Port() const { return impl_->port; }

std::string ViewerServer::Url() const {
  return "http://" + impl_->options.address + ":" + std::to_string(impl_->port) + "/";
}

void ViewerServer::Stop() {
  if (!thread_.joinable()) return;
  // In order on the server thread: close everything, then end run() (handlers still pending are
  // destroyed with the io_context, not run).
  asio::post(impl_->io, [impl = impl_.get()] { impl->CloseAll(); });
  asio::post(impl_->io, [impl = impl_.get()] { impl->io.stop(); });
  thread_.join();
}

}  // namespace ubersim::viewer
