// SPDX-License-Identifier: Apache-2.0
#include "sync_server.hpp"

#include <array>
#include <stdexcept>

#include <boost/asio/buffer.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>

#include "transport_common/delimited.hpp"
#include "mapping.hpp"

namespace ubersim::ssl_simulation {

namespace asio = boost::asio;
using transport::DelimitedDecoder;
using transport::EncodeDelimited;
using asio::ip::tcp;

/// One client: reads frames, hands each request to the worker, writes the reply, reads on.
/// At most one request per client is in flight, so replies keep the order of the requests.
class SyncConnection : public std::enable_shared_from_this<SyncConnection> {
 public:
  SyncConnection(tcp::socket socket, SyncServer& server)
      : socket_(std::move(socket)), server_(server), decoder_(server.max_message_) {
    boost::system::error_code ec;
    const auto remote = socket_.remote_endpoint(ec);
    peer_ = ec ? std::string("?") : remote.address().to_string() + ":" + std::to_string(remote.port());
  }

  void Start() { TakeBuffered(); }
  const std::string& Peer() const { return peer_; }

  // Called on the io thread with the worker's answer.
  void Reply(const std::string& payload) {
    out_ = EncodeDelimited(payload);
    asio::async_write(socket_, asio::buffer(out_),
                      [self = shared_from_this()](boost::system::error_code ec, std::size_t) {
                        if (ec) {
                          self->Close("write failed: " + ec.message());
                          return;
                        }
                        self->TakeBuffered();
                      });
  }

  void Close(const std::string& why) {
    if (closed_) return;
    closed_ = true;
    if (!why.empty()) server_.log_.Warning("sync client " + peer_ + " closed: " + why);
    boost::system::error_code ec;
    socket_.shutdown(tcp::socket::shutdown_both, ec);
    socket_.close(ec);
    server_.Forget(this);
  }

 private:
  // Handles the next complete frame, or reads more.
  void TakeBuffered() {
    std::string message;
    std::string error;
    switch (decoder_.Next(message, error)) {
      case DelimitedDecoder::Status::kError:
        Close("bad framing: " + error);
        return;
      case DelimitedDecoder::Status::kNeedMore:
        Read();
        return;
      case DelimitedDecoder::Status::kMessage: {
        SimulationSyncRequest request;
        if (auto e = ParseMessage(message.data(), message.size(), server_.max_message_, request)) {
          Close("bad request: " + e->code + ": " + e->message);
          return;
        }
        server_.Enqueue(shared_from_this(), std::move(request));
        return;
      }
    }
  }

  void Read() {
    socket_.async_read_some(asio::buffer(chunk_),
                            [self = shared_from_this()](boost::system::error_code ec, std::size_t n) {
                              if (ec) {
                                // An orderly close by the client is not worth a warning.
                                self->Close(ec == asio::error::eof || ec == asio::error::operation_aborted
                                                ? std::string()
                                                : "read failed: " + ec.message());
                                return;
                              }
                              self->decoder_.Append(std::string_view(self->chunk_.data(), n));
                              self->TakeBuffered();
                            });
  }

  tcp::socket socket_;
  SyncServer& server_;
  DelimitedDecoder decoder_;
  std::array<char, 4096> chunk_{};
  std::string out_;
  std::string peer_;
  bool closed_ = false;
};

SyncServer::SyncServer(asio::io_context& io, const std::string& address, std::uint16_t port,
                       std::size_t max_message, std::size_t max_clients, Log& log, Handler handler)
    : io_(io),
      acceptor_(io),
      max_message_(max_message),
      max_clients_(max_clients),
      log_(log),
      handler_(std::move(handler)),
      port_(port) {
  boost::system::error_code ec;
  const asio::ip::address ip = asio::ip::make_address(address, ec);
  if (ec) throw std::runtime_error("'" + address + "' is not an IP address");
  const tcp::endpoint local(ip, port);
  acceptor_.open(local.protocol(), ec);
  if (!ec) acceptor_.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) acceptor_.bind(local, ec);
  if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error("cannot listen on tcp " + address + ":" + std::to_string(port) + ": " + ec.message());
}

SyncServer::~SyncServer() { StopWorker(); }

void SyncServer::Start() {
  worker_ = std::thread([this] { WorkerLoop(); });
  Accept();
}

void SyncServer::StopWorker() {
  {
    std::lock_guard lock(jobs_mutex_);
    stopping_ = true;
  }
  jobs_ready_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void SyncServer::Accept() {
  acceptor_.async_accept([this](boost::system::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || ec == asio::error::bad_descriptor) return;
    if (!ec) {
      if (connections_.size() >= max_clients_) {
        log_.Warning("sync client refused: already " + std::to_string(max_clients_) + " connected");
        boost::system::error_code ignored;
        socket.close(ignored);
      } else {
        socket.set_option(tcp::no_delay(true), ec);
        auto c = std::make_shared<SyncConnection>(std::move(socket), *this);
        connections_.insert(c);
        log_.Info("sync client " + c->Peer() + " connected");
        c->Start();
      }
    }
    Accept();
  });
}

void SyncServer::Forget(SyncConnection* connection) {
  for (auto it = connections_.begin(); it != connections_.end(); ++it) {
    if (it->get() == connection) {
      connections_.erase(it);
      return;
    }
  }
}

void SyncServer::Enqueue(std::shared_ptr<SyncConnection> connection, SimulationSyncRequest request) {
  {
    std::lock_guard lock(jobs_mutex_);
    jobs_.push_back(Job{connection, std::move(request)});
  }
  jobs_ready_.notify_one();
}

void SyncServer::WorkerLoop() {
  for (;;) {
    Job job;
    {
      std::unique_lock lock(jobs_mutex_);
      jobs_ready_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
      if (stopping_) return;
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    if (job.connection.expired()) continue;
    std::string payload;
    try {
      handler_(job.request).SerializeToString(&payload);
    } catch (const std::exception& e) {
      log_.Error(std::string("sync request failed: ") + e.what());
      SimulationSyncResponse().SerializeToString(&payload);
    }
    // Back to the io thread, which owns the socket.
    asio::post(io_, [weak = job.connection, payload = std::move(payload)] {
      if (auto c = weak.lock()) c->Reply(payload);
    });
  }
}

}  // namespace ubersim::ssl_simulation
