// SPDX-License-Identifier: Apache-2.0
// Synchronous simulation over TCP: clients send varint-delimited SimulationSyncRequests and get
// one SimulationSyncResponse each. Sockets live on the io_context thread; requests run one at a
// time on a worker thread, because each one blocks until the simulation thread has stepped.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include <ubersim/log.hpp>

#include "ssl_simulation_synchronous.pb.h"

namespace ubersim::ssl_simulation {

class SyncConnection;

/// TCP server for SimulationSyncRequest → SimulationSyncResponse.
class SyncServer {
 public:
  /// Runs one request on the worker thread and returns its response.
  using Handler = std::function<SimulationSyncResponse(const SimulationSyncRequest&)>;

  /// Listens on address:port (throws std::runtime_error when it cannot); `max_message`: largest
  /// request accepted, bytes; `max_clients`: connections served at once.
  SyncServer(boost::asio::io_context& io, const std::string& address, std::uint16_t port,
             std::size_t max_message, std::size_t max_clients, Log& log, Handler handler);
  ~SyncServer();
  SyncServer(const SyncServer&) = delete;
  SyncServer& operator=(const SyncServer&) = delete;

  /// Starts accepting and the worker thread.
  void Start();
  /// Stops the worker (joins it). Sockets close when the io_context stops and this is destroyed.
  void StopWorker();
  /// The bound port.
  std::uint16_t Port() const { return port_; }

 private:
  friend class SyncConnection;
  struct Job {
    std::weak_ptr<SyncConnection> connection;
    SimulationSyncRequest request;
  };
  void Accept();
  void Enqueue(std::shared_ptr<SyncConnection> connection, SimulationSyncRequest request);
  void Forget(SyncConnection* connection);
  void WorkerLoop();

  boost::asio::io_context& io_;
  boost::asio::ip::tcp::acceptor acceptor_;
  std::size_t max_message_;
  std::size_t max_clients_;
  Log& log_;
  Handler handler_;
  std::uint16_t port_;
  std::set<std::shared_ptr<SyncConnection>> connections_;  // io thread only

  std::mutex jobs_mutex_;
  std::condition_variable jobs_ready_;
  std::deque<Job> jobs_;
  bool stopping_ = false;
  std::thread worker_;
};

}  // namespace ubersim::ssl_simulation
