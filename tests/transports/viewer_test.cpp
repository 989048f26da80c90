// SPDX-License-Identifier: Apache-2.0
// The viewer transport: its messages, its HTTP + WebSocket server over real loopback sockets, and
// the plugin inside a real world (commands from a WebSocket reach the kernel; what the page gets
// matches the world; a Referee datagram on loopback multicast reaches the page). The referee
// JSON and its relay are in viewer_referee_test.cpp; the browser end-to-end test is
// tests/interfaces/test_viewer.py.
#include <sys/socket.h>
#include <sys/time.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <regex>
#include <span>
#include <sstream>
#include <string>
#include <thread>
#include <utility>  // before Boost.Asio: its 1.74 headers use std::exchange without it

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <gtest/gtest.h>
#include <rapidjson/document.h>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/world.hpp"
#include "referee_datagram.hpp"
#include "transport_common/multicast_sender.hpp"
#include "viewer_protocol.hpp"
#include "viewer_server.hpp"
#include "viewer_ws_client.hpp"
#include "web_assets.hpp"

namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using namespace ubersim;
using namespace ubersim::viewer;

rapidjson::Document Parse(const std::string& text) { return ubersim::testing::ParseJson(text); }
using ubersim::testing::ReceiveTimeout;
using ubersim::testing::WsClient;

// ---------------------------------------------------------------- messages

TEST(ViewerProtocol, DecodesTheClockCommands) {
  const CommandLimits limits;
  DecodedCommand c = DecodeCommand(R"({"cmd":"pause","id":7})", limits);
  ASSERT_TRUE(c.error.empty()) << c.error;
  ASSERT_EQ(c.events.size(), 1u);
  EXPECT_EQ(std::get<ClockEvent>(c.events[0]).action, ClockEvent::Action::kPause);
  EXPECT_EQ(c.id, 7);
  EXPECT_EQ(c.paused, true);

  c = DecodeCommand(R"({"cmd":"resume"})", limits);
  EXPECT_EQ(std::get<ClockEvent>(c.events.at(0)).action, ClockEvent::Action::kResume);
  EXPECT_EQ(c.paused, false);

  c = DecodeCommand(R"({"cmd":"step","steps":16})", limits);
  EXPECT_EQ(std::get<ClockEvent>(c.events.at(0)).action, ClockEvent::Action::kStep);
  EXPECT_EQ(std::get<ClockEvent>(c.events.at(0)).steps, 16);

  c = DecodeCommand(R"({"cmd":"speed","factor":0.25})", limits);
  EXPECT_EQ(std::get<ClockEvent>(c.events.at(0)).action, ClockEvent::Action::kSetSpeed);
  EXPECT_DOUBLE_EQ(std::get<ClockEvent>(c.events.at(0)).speed_factor, 0.25);
  EXPECT_EQ(c.speed_factor, 0.25);

  c = DecodeCommand(R"({"cmd":"reset"})", limits);
  EXPECT_EQ(std::get<ClockEvent>(c.events.at(0)).action, ClockEvent::Action::kReset);
}

TEST(ViewerProtocol, AMovePlacesTheBallOrARobotAtRest) {
  const CommandLimits limits;
  DecodedCommand c = DecodeCommand(R"({"cmd":"move","target":"ball","x":1.5,"y":-0.25})", limits);
  ASSERT_TRUE(c.error.empty()) << c.error;
  const auto& ball = std::get<PositionEvent>(c.events.at(0));
  EXPECT_TRUE(ball.target.is_ball);
  EXPECT_EQ(*ball.position, Vec3(1.5, -0.25, 0.0));
  EXPECT_EQ(*ball.velocity, Vec3::Zero());
  EXPECT_EQ(*ball.angular_velocity, Vec3::Zero());

  c = DecodeCommand(R"({"cmd":"move","target":{"team":"yellow","id":3},"x":-2,"y":1,"yaw":1.5})", limits);
  ASSERT_TRUE(c.error.empty()) << c.error;
  const auto& robot = std::get<PositionEvent>(c.events.at(0));
  EXPECT_FALSE(robot.target.is_ball);
  EXPECT_EQ(robot.target.robot, (RobotId{Team::kYellow, 3}));
  EXPECT_EQ(robot.position->x(), -2.0);
  EXPECT_EQ(robot.position->y(), 1.0);
  EXPECT_EQ(*robot.yaw, 1.5);
  EXPECT_EQ(*robot.velocity, Vec3::Zero());

  c = DecodeCommand(R"({"cmd":"move","target":{"team":"blue","id":0},"x":0,"y":0})", limits);
  EXPECT_FALSE(std::get<PositionEvent>(c.events.at(0)).yaw.has_value()) << "no yaw: keep the heading";
}

TEST(ViewerProtocol, AKickSetsTheBallVelocity) {
  const DecodedCommand c = DecodeCommand(R"({"cmd":"kick","vx":3,"vy":-4,"vz":1})", CommandLimits{});
  ASSERT_TRUE(c.error.empty()) << c.error;
  const auto& e = std::get<PositionEvent>(c.events.at(0));
  EXPECT_TRUE(e.target.is_ball);
  EXPECT_FALSE(e.position.has_value()) << "a kick leaves the ball where it is";
  EXPECT_EQ(*e.velocity, Vec3(3, -4, 1));
}

TEST(ViewerProtocol, RefusesBadCommandsSayingWhy) {
  CommandLimits limits;
  limits.half_length = 5.0;
  limits.half_width = 3.5;
  const std::pair<const char*, const char*> cases[] = {
      {"", "not JSON"},
      {"{\"cmd\":\"pause\"", "not JSON"},
      {"{\"cmd\":\"pause\"} trailing", "not JSON"},
      {"[1,2]", "must be a JSON object"},
      {"{}", "'cmd' is missing"},
      {"{\"cmd\":5}", "'cmd' is missing or not a string"},
      {"{\"cmd\":\"explode\"}", "unknown command 'explode'"},
      {"{\"cmd\":\"step\",\"steps\":0}", "'steps' must be an integer"},
      {"{\"cmd\":\"step\",\"steps\":1.5}", "'steps' must be an integer"},
      {"{\"cmd\":\"speed\"}", "'factor' is missing"},
      {"{\"cmd\":\"speed\",\"factor\":-1}", "'factor' must be 0"},
      {"{\"cmd\":\"speed\",\"factor\":\"fast\"}", "'factor' must be a finite number"},
      {"{\"cmd\":\"move\",\"x\":0,\"y\":0}", "'target' is missing"},
      {"{\"cmd\":\"move\",\"target\":\"goal\",\"x\":0,\"y\":0}", "'target' must be \"ball\""},
      {"{\"cmd\":\"move\",\"target\":{\"team\":\"red\",\"id\":1},\"x\":0,\"y\":0}", "not \"red\""},
      {"{\"cmd\":\"move\",\"target\":{\"team\":\"blue\",\"id\":16},\"x\":0,\"y\":0}", "'target.id' must be an integer 0..15"},
      {"{\"cmd\":\"move\",\"target\":\"ball\",\"y\":0}", "'x' is missing"},
      {"{\"cmd\":\"move\",\"target\":\"ball\",\"x\":5.1,\"y\":0}", "off the carpet"},
      {"{\"cmd\":\"move\",\"target\":\"ball\",\"x\":0,\"y\":-3.6}", "off the carpet"},
      {"{\"cmd\":\"move\",\"target\":\"ball\",\"x\":1e999,\"y\":0}", "not JSON"},
      {"{\"cmd\":\"kick\",\"vx\":10,\"vy\":1}", "kick speed"},
      {"{\"cmd\":\"kick\",\"vx\":1,\"vy\":1,\"vz\":-1}", "'vz' must be >= 0"},
      {"{\"cmd\":\"kick\",\"vx\":1}", "'vy' is missing"},
  };
  for (const auto& [text, expected] : cases) {
    const DecodedCommand c = DecodeCommand(text, limits);
    EXPECT_NE(c.error.find(expected), std::string::npos) << text << " → " << c.error;
    EXPECT_TRUE(c.events.empty()) << text;
    EXPECT_FALSE(c.speed_factor.has_value()) << text;
  }
}

TEST(ViewerProtocol, TheStateMessageCarriesTheSampleFramesAndStatus) {
  WorldSample s;
  s.step = 2000;
  s.sim_time_ns = 2'000'000'000;
  s.ball_position = Vec3(0.5, -0.25, 0.1);
  s.ball_velocity = Vec3(1, 2, std::nan(""));
  RobotSample r;
  r.id = RobotId{Team::kYellow, 4};
  r.x = 1.25;
  r.y = -2;
  r.yaw = 0.5;
  r.contact = true;
  r.has_drive = true;
  r.wheel_speeds = {12.5, -7.25};
  r.drive_forward = 0.75;
  r.drive_left = -0.5;
  r.drive_angular = 1.5;
  s.robots.push_back(r);
  RobotSample without_drive;
  without_drive.id = RobotId{Team::kYellow, 5};
  s.robots.push_back(without_drive);
  VisionFrame f;
  f.camera_id = 2;
  f.frame_number = 99;
  f.t_capture_ns = 1'965'000'000;
  f.t_sent_ns = 2'000'000'000;
  f.balls.push_back(DetectedBall{0.51, -0.24, 0, 1});
  f.robots.push_back(DetectedRobot{RobotId{Team::kYellow, 4}, 1.26, -2.01, 0.49, 1});
  ViewerStatus status;
  status.real_time_factor = 1.5;
  status.vision_rate = 75;
  status.cameras = 1;
  status.clients = 3;
  status.paused = true;

  const rapidjson::Document d = Parse(EncodeState(s, {f}, status));
  EXPECT_STREQ(d["type"].GetString(), "state");
  EXPECT_EQ(d["step"].GetInt64(), 2000);
  EXPECT_DOUBLE_EQ(d["t"].GetDouble(), 2.0);
  EXPECT_DOUBLE_EQ(d["step_dt"].GetDouble(), 0.001);
  EXPECT_DOUBLE_EQ(d["ball"]["x"].GetDouble(), 0.5);
  EXPECT_DOUBLE_EQ(d["ball"]["z"].GetDouble(), 0.1);
  EXPECT_TRUE(d["ball"]["vz"].IsNull()) << "JSON has no NaN: a broken value goes out as null";
  ASSERT_EQ(d["robots"].Size(), 2u);
  EXPECT_STREQ(d["robots"][0]["team"].GetString(), "yellow");
  EXPECT_EQ(d["robots"][0]["id"].GetInt(), 4);
  EXPECT_DOUBLE_EQ(d["robots"][0]["x"].GetDouble(), 1.25);
  EXPECT_TRUE(d["robots"][0]["contact"].GetBool());
  // The drive's own measurements, for the page's robot panel; null for a robot without a drive.
  const auto& drive = d["robots"][0]["drive"];
  ASSERT_TRUE(drive.IsObject());
  EXPECT_DOUBLE_EQ(drive["forward"].GetDouble(), 0.75);
  EXPECT_DOUBLE_EQ(drive["left"].GetDouble(), -0.5);
  EXPECT_DOUBLE_EQ(drive["angular"].GetDouble(), 1.5);
  ASSERT_EQ(drive["wheels"].Size(), 2u);
  EXPECT_DOUBLE_EQ(drive["wheels"][0].GetDouble(), 12.5);
  EXPECT_DOUBLE_EQ(drive["wheels"][1].GetDouble(), -7.25);
  EXPECT_TRUE(d["robots"][1]["drive"].IsNull());
  ASSERT_EQ(d["vision"].Size(), 1u);
  EXPECT_EQ(d["vision"][0]["camera"].GetInt(), 2);
  EXPECT_DOUBLE_EQ(d["vision"][0]["t_capture"].GetDouble(), 1.965);
  EXPECT_DOUBLE_EQ(d["vision"][0]["robots"][0]["x"].GetDouble(), 1.26);
  EXPECT_DOUBLE_EQ(d["vision"][0]["balls"][0]["y"].GetDouble(), -0.24);
  EXPECT_DOUBLE_EQ(d["status"]["rtf"].GetDouble(), 1.5);
  EXPECT_EQ(d["status"]["clients"].GetInt(), 3);
  EXPECT_TRUE(d["status"]["paused"].GetBool());
  EXPECT_TRUE(d["status"]["speed"].IsNull());
  EXPECT_TRUE(d["status"]["referee_age"].IsNull()) << "no Referee message yet";
  status.referee_age = 2.5;
  EXPECT_DOUBLE_EQ(Parse(EncodeState(s, {}, status))["status"]["referee_age"].GetDouble(), 2.5);
}

TEST(ViewerProtocol, TheHelloCarriesTheFieldAndCameras) {
  FieldGeometry field;
  field.name = "div-b";
  field.field_length = 9;
  field.carpet_width = 6.6;
  field.lines.push_back(FieldLine{"TopTouchLine", -4.5, 3, 4.5, 3, 0.01});
  field.arcs.push_back(FieldArc{"CenterCircle", 0, 0, 0.5, 0, 6.28, 0.01});
  const rapidjson::Document d =
      Parse(EncodeHello("my world", 60, field, {CameraInfo{1, Vec3(0, 1, 6)}}));
  EXPECT_STREQ(d["type"].GetString(), "hello");
  EXPECT_STREQ(d["world"].GetString(), "my world");
  EXPECT_DOUBLE_EQ(d["field"]["field_length"].GetDouble(), 9);
  EXPECT_DOUBLE_EQ(d["field"]["carpet_width"].GetDouble(), 6.6);
  EXPECT_STREQ(d["field"]["lines"][0]["name"].GetString(), "TopTouchLine");
  EXPECT_DOUBLE_EQ(d["field"]["arcs"][0]["radius"].GetDouble(), 0.5);
  EXPECT_EQ(d["cameras"][0]["id"].GetInt(), 1);
  EXPECT_DOUBLE_EQ(d["cameras"][0]["z"].GetDouble(), 6);
  EXPECT_TRUE(d["referee"].IsNull()) << "no referee socket: the page shows no match";
  const rapidjson::Document with = Parse(EncodeHello("w", 60, field, {}, "224.5.23.1:10003"));
  EXPECT_STREQ(with["referee"].GetString(), "224.5.23.1:10003");
}

// A replay (`ubersim replay --viewer`): the hello names the log, the status says where it stands,
// and the page's commands are seek, play, pause and speed, nothing that would change a world.
TEST(ViewerProtocol, AReplaysHelloStatusAndCommands) {
  FieldGeometry field;
  field.field_length = 12;
  ReplayInfo info;
  info.file = "final.log.gz";
  info.duration = 600.5;
  info.start_unix = 1700000000.25;
  info.sending = true;
  const rapidjson::Document hello = Parse(EncodeHello("final.log.gz", 60, field, {}, "log", &info));
  ASSERT_TRUE(hello.HasMember("replay"));
  EXPECT_STREQ(hello["replay"]["file"].GetString(), "final.log.gz");
  EXPECT_DOUBLE_EQ(hello["replay"]["duration"].GetDouble(), 600.5);
  EXPECT_DOUBLE_EQ(hello["replay"]["start_unix"].GetDouble(), 1700000000.25);
  EXPECT_TRUE(hello["replay"]["sending"].GetBool());
  EXPECT_DOUBLE_EQ(hello["replay"]["min_speed"].GetDouble(), 0.25);
  EXPECT_DOUBLE_EQ(hello["replay"]["max_speed"].GetDouble(), 8);
  EXPECT_FALSE(Parse(EncodeHello("w", 60, field, {}))
                   .HasMember("replay")) << "a live world's hello has no replay: the page shows no slider";

  ViewerStatus status;
  EXPECT_FALSE(Parse(EncodeState(WorldSample{}, {}, status))["status"].HasMember("replay"));
  status.replay = ReplayStatus{12.5, 600.5, 2, true};
  const rapidjson::Document state = Parse(EncodeState(WorldSample{}, {}, status));
  const auto& r = state["status"]["replay"];
  EXPECT_DOUBLE_EQ(r["t"].GetDouble(), 12.5);
  EXPECT_DOUBLE_EQ(r["duration"].GetDouble(), 600.5);
  EXPECT_DOUBLE_EQ(r["speed"].GetDouble(), 2);
  EXPECT_TRUE(r["playing"].GetBool());

  ReplayCommand c = DecodeReplayCommand(R"({"cmd":"seek","t":42.25,"id":3})", info);
  ASSERT_TRUE(c.error.empty()) << c.error;
  EXPECT_EQ(c.seek, 42.25);
  EXPECT_EQ(c.id, 3);
  EXPECT_FALSE(c.playing || c.speed);
  EXPECT_EQ(DecodeReplayCommand(R"({"cmd":"seek","t":-1})", info).seek, 0.0) << "clamped to the log";
  EXPECT_EQ(DecodeReplayCommand(R"({"cmd":"seek","t":1e6})", info).seek, 600.5);
  EXPECT_EQ(DecodeReplayCommand(R"({"cmd":"play"})", info).playing, true);
  EXPECT_EQ(DecodeReplayCommand(R"({"cmd":"resume"})", info).playing, true);
  EXPECT_EQ(DecodeReplayCommand(R"({"cmd":"pause"})", info).playing, false);
  EXPECT_EQ(DecodeReplayCommand(R"({"cmd":"speed","factor":0.25})", info).speed, 0.25);
  EXPECT_EQ(DecodeReplayCommand(R"({"cmd":"speed","factor":8})", info).speed, 8.0);
  const std::pair<const char*, const char*> refused[] = {
      {"{\"cmd\":\"seek\"", "not JSON"},
      {"[]", "must be a JSON object"},
      {"{\"cmd\":\"seek\"}", "'t' is missing"},
      {"{\"cmd\":\"seek\",\"t\":\"end\"}", "'t' must be a finite number"},
      {"{\"cmd\":\"speed\",\"factor\":0}", "'factor' must be 0.25 to 8"},
      {"{\"cmd\":\"speed\",\"factor\":16}", "'factor' must be 0.25 to 8"},
      {"{\"cmd\":\"move\",\"target\":\"ball\",\"x\":0,\"y\":0}", "a replay shows a log as it was recorded"},
      {"{\"cmd\":\"reset\"}", "a replay shows a log"},
      {"{\"cmd\":\"rewind\"}", "unknown command 'rewind' (seek, play, pause, speed)"},
  };
  for (const auto& [text, expected] : refused) {
    c = DecodeReplayCommand(text, info);
    EXPECT_NE(c.error.find(expected), std::string::npos) << text << " → " << c.error;
    EXPECT_FALSE(c.seek || c.playing || c.speed) << text;
  }
}

// ---------------------------------------------------------------- server

struct HttpResult {
  unsigned status = 0;
  std::string content_type;
  std::string body;
};

HttpResult HttpRequest(std::uint16_t port, http::verb verb, const std::string& target) {
  asio::io_context io;
  tcp::socket socket(io);
  socket.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  ReceiveTimeout(socket, 10);
  http::request<http::string_body> req{verb, target, 11};
  req.set(http::field::host, "127.0.0.1");
  req.prepare_payload();
  http::write(socket, req);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.skip(verb == http::verb::head);  // a HEAD reply announces a body it does not send
  http::read(socket, buffer, parser);
  const auto& res = parser.get();
  return HttpResult{res.result_int(), std::string(res[http::field::content_type]), res.body()};
}

struct ViewerServerTest : ::testing::Test {
  std::ostringstream log_text;
  kernel::StreamLog log{log_text, LogLevel::kDebug};
  std::atomic<int> ticks{0};
  std::vector<std::string> catch_up;  // what a new client gets after the hello
  std::unique_ptr<ViewerServer> server;

  void StartServer(int max_clients = 16) {
    ViewerServer::Options o;
    o.port = 0;
    o.max_clients = max_clients;
    ViewerServer::Callbacks cb;
    cb.hello = [] { return std::string(R"({"type":"hello"})"); };
    cb.catch_up = [this] { return catch_up; };
    cb.on_message = [](std::string_view text) {
      return R"({"type":"ack","echo":")" + std::string(text) + "\"}";
    };
    cb.latest_state = [] { return std::string(R"({"type":"state","t":1.5})"); };
    cb.tick = [this] { ++ticks; };
    server = std::make_unique<ViewerServer>(o, std::move(cb), std::chrono::milliseconds(5), log);
    server->Start();
  }
  void WaitForClients(int n) {
    for (int i = 0; i < 1000 && server->Clients() != n; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_EQ(server->Clients(), n);
  }
};

TEST_F(ViewerServerTest, ServesEveryFileOfThePageAndTheState) {
  StartServer();
  ASSERT_NE(FindWebAsset("/index.html"), nullptr);
  ASSERT_EQ(FindWebAsset("/"), FindWebAsset("/index.html"));
  for (const WebAsset& a : WebAssets()) {
    const HttpResult r = HttpRequest(server->Port(), http::verb::get, std::string(a.path) + "?v=1");
    EXPECT_EQ(r.status, 200u) << a.path;
    EXPECT_EQ(r.content_type, a.content_type) << a.path;
    EXPECT_EQ(r.body, a.body) << a.path;
  }
  const HttpResult page = HttpRequest(server->Port(), http::verb::get, "/");
  EXPECT_EQ(page.content_type, "text/html; charset=utf-8");
  EXPECT_NE(page.body.find("<canvas"), std::string::npos);
  EXPECT_EQ(page.body.find("http://"), std::string::npos) << "the page must load nothing from elsewhere";
  EXPECT_EQ(page.body.find("https://"), std::string::npos) << "the page must load nothing from elsewhere";

  const HttpResult state = HttpRequest(server->Port(), http::verb::get, "/api/state");
  EXPECT_EQ(state.status, 200u);
  EXPECT_EQ(state.content_type, "application/json");
  EXPECT_EQ(state.body, R"({"type":"state","t":1.5})");

  EXPECT_EQ(HttpRequest(server->Port(), http::verb::get, "/missing.js").status, 404u);
  EXPECT_EQ(HttpRequest(server->Port(), http::verb::post, "/").status, 405u);
  const HttpResult head = HttpRequest(server->Port(), http::verb::head, "/");
  EXPECT_EQ(head.status, 200u);
  EXPECT_TRUE(head.body.empty());
}

TEST_F(ViewerServerTest, AWebSocketGetsTheHelloThenStatesAndRepliesToItsCommands) {
  StartServer();
  WsClient client(server->Port());
  EXPECT_EQ(client.Read(), R"({"type":"hello"})");
  WaitForClients(1);
  client.Send("pause");
  EXPECT_EQ(client.Read(), R"({"type":"ack","echo":"pause"})");
  server->Broadcast(std::make_shared<const std::string>("state 1"));
  EXPECT_EQ(client.Read(), "state 1");
  EXPECT_GT(ticks.load(), 0);
  client.ws.close(websocket::close_code::normal);
  WaitForClients(0);
}

TEST_F(ViewerServerTest, RefusesBrowsersOverTheLimitUntilOneLeaves) {
  StartServer(/*max_clients=*/1);
  auto first = std::make_unique<WsClient>(server->Port());
  first->Read();
  WaitForClients(1);
  EXPECT_THROW(WsClient second(server->Port()), boost::system::system_error);
  first->ws.close(websocket::close_code::normal);
  first.reset();
  WaitForClients(0);
  WsClient third(server->Port());
  EXPECT_EQ(third.Read(), R"({"type":"hello"})");
}

TEST_F(ViewerServerTest, ASlowBrowserOnlyEverHasTheNewestStateWaiting) {
  StartServer();
  WsClient slow(server->Port());
  slow.Read();
  WaitForClients(1);
  // 400 states of 64 kB while the page reads nothing: queued, that would be 25 MB.
  const std::string filler(64 * 1024, 'x');
  constexpr int kStates = 400;
  for (int i = 0; i < kStates; ++i) {
    server->Broadcast(std::make_shared<const std::string>(std::to_string(i) + " " + filler));
  }
  server->Broadcast(std::make_shared<const std::string>("last"));
  int received = 0;
  std::string message;
  while ((message = slow.Read()) != "last") ++received;
  // What the socket buffers held when the page stopped reading, plus the newest: far fewer.
  EXPECT_LT(received, kStates / 4) << "states were queued for a page that did not read";
}

TEST_F(ViewerServerTest, StatesNeverPushOutAWaitingRefereeMessageAndANewPageCatchesUp) {
  catch_up = {R"({"type":"referee","command":"STOP"})"};
  StartServer();
  WsClient slow(server->Port());
  EXPECT_EQ(slow.Read(), R"({"type":"hello"})");
  EXPECT_EQ(slow.Read(), R"({"type":"referee","command":"STOP"})") << "the latest match state at once";
  WaitForClients(1);
  // A referee message among many large states to a page that reads nothing for a while.
  const std::string filler(64 * 1024, 'x');
  for (int i = 0; i < 100; ++i) server->Broadcast(std::make_shared<const std::string>("state " + filler));
  server->Broadcast(std::make_shared<const std::string>("referee 1"), ViewerServer::Channel::kReferee);
  for (int i = 0; i < 100; ++i) server->Broadcast(std::make_shared<const std::string>("state " + filler));
  server->Broadcast(std::make_shared<const std::string>("last"));
  int referees = 0;
  std::string message;
  while ((message = slow.Read()) != "last") referees += message == "referee 1";
  EXPECT_EQ(referees, 1) << "the referee message has its own slot: replaced only by a newer one";
}

TEST_F(ViewerServerTest, ABusyPortIsRefusedNamingTheAddress) {
  StartServer();
  ViewerServer::Options o;
  o.port = server->Port();
  try {
    ViewerServer second(o, {}, std::chrono::milliseconds(5), log);
    FAIL() << "a second server bound the same port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot listen on 127.0.0.1:" + std::to_string(o.port)),
              std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--no-viewer"), std::string::npos) << e.what();
  }
}

TEST_F(ViewerServerTest, ClosesAPageThatSendsAndNeverReads) {
  StartServer();
  WsClient flooder(server->Port());
  flooder.Read();
  WaitForClients(1);
  // Large commands fill the server's replies queue (each reply echoes its command).
  const std::string command(32 * 1024, 'c');
  bool closed = false;
  for (int i = 0; i < 2000 && !closed; ++i) {
    beast::error_code ec;
    flooder.ws.write(asio::buffer(command), ec);
    closed = static_cast<bool>(ec);
  }
  WaitForClients(0);
  EXPECT_NE(log_text.str().find("does not read the replies"), std::string::npos) << log_text.str();
}

// ---------------------------------------------------------------- the plugin in a world

struct ViewerWorld : ::testing::Test {
  std::ostringstream log_text;
  kernel::StreamLog log{log_text, LogLevel::kWarning};
  kernel::PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  std::unique_ptr<kernel::World> world;
  std::uint16_t port = 0;

  void SetUp() override { Build(R"({"port": 0, "rate": 200})"); }

  // The Div B world with only a viewer of these parameters, local-only (as `--local-only`: the
  // viewer's referee socket joins its group on loopback alone, never on a real interface).
  void Build(const std::string& viewer_params) {
    const kernel::ModelLoader loader(kernel::ModelLoader::DefaultSchemaDir(),
                                     [this](PluginKind k, const std::string& id) {
                                       return registry.Find(k, id).schema_json;
                                     });
    kernel::WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml");
    model.transports.clear();
    model.transports.push_back(kernel::TransportModel{"viewer", ParamView::FromJson(viewer_params)});
    model.local_only = true;
    world = std::make_unique<kernel::World>(model, registry, log);
    const std::vector<std::string> endpoints = world->TransportEndpoints();
    ASSERT_EQ(endpoints.size(), 1u);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(endpoints[0], m, std::regex(R"(http://127\.0\.0\.1:(\d+)/)")))
        << endpoints[0];
    port = static_cast<std::uint16_t>(std::stoi(m[1]));
  }

  // Steps (or, paused, only handles events) until a state message satisfies `done`. The viewer
  // sends a state every 5 ms (rate 200) whether or not the world steps.
  rapidjson::Document StateWhere(WsClient& client, const std::function<bool(const rapidjson::Document&)>& done,
                                 bool step) {
    for (int i = 0; i < 2000; ++i) {
      if (step) {
        world->Step();
      } else {
        world->ProcessEvents();
      }
      rapidjson::Document d = client.ReadType("state");
      if (d.IsObject() && done(d)) return d;
    }
    ADD_FAILURE() << "no state message matched";
    return {};
  }
};

TEST_F(ViewerWorld, AWorldThatHasNotSteppedIsSeenAndAResetShowsAtOnce) {
  // As `ubersim run --paused` leaves it: built, never stepped.
  WsClient page(port);
  page.ReadType("hello");
  const auto at_start = [](const rapidjson::Document& d) { return d["robots"].Size() == 12 && d["t"].GetDouble() == 0.0; };
  ASSERT_TRUE(StateWhere(page, at_start, false).IsObject());
  // Stepped on, then reset while paused: the page shows the start again without a step.
  world->clock_control().paused = true;
  for (int i = 0; i < 300; ++i) world->Step();
  ASSERT_TRUE(StateWhere(page, [](const rapidjson::Document& d) { return d["t"].GetDouble() > 0.29; }, false).IsObject());
  page.Send(R"({"cmd":"move","target":"ball","x":2.0,"y":1.0})");
  page.ReadType("ack");
  page.Send(R"({"cmd":"reset"})");
  page.ReadType("ack");
  const rapidjson::Document reset = StateWhere(page, at_start, false);
  ASSERT_TRUE(reset.IsObject());
  EXPECT_NEAR(reset["ball"]["x"].GetDouble(), world->model().ball_start.x(), 1e-9);
  EXPECT_EQ(world->clock().steps(), 0);
}

TEST_F(ViewerWorld, APageSeesTheWorldAndItsCommandsReachTheKernel) {
  WsClient page(port);
  const rapidjson::Document hello = page.ReadType("hello");
  EXPECT_STREQ(hello["world"].GetString(), "div-b");
  EXPECT_DOUBLE_EQ(hello["field"]["field_length"].GetDouble(), world->model().field->geometry.field_length);
  EXPECT_EQ(hello["cameras"].Size(), world->model().perception.cameras.size());

  // The robots and the ball as the page gets them are the world's.
  const rapidjson::Document state =
      StateWhere(page, [](const rapidjson::Document& d) { return d["t"].GetDouble() > 0.05; }, true);
  ASSERT_TRUE(state.IsObject());
  const WorldSnapshot truth = world->GroundTruth();
  ASSERT_EQ(state["robots"].Size(), truth.robots.size());
  for (rapidjson::SizeType i = 0; i < state["robots"].Size(); ++i) {
    const auto& r = state["robots"][i];
    EXPECT_STREQ(r["team"].GetString(), ToString(truth.robots[i].id.team));
    EXPECT_EQ(r["id"].GetInt(), truth.robots[i].id.id);
    // The robots stand still at kick-off; the page lags the world by at most a few steps.
    EXPECT_NEAR(r["x"].GetDouble(), truth.robots[i].pose.position.x(), 1e-3);
    EXPECT_NEAR(r["y"].GetDouble(), truth.robots[i].pose.position.y(), 1e-3);
    // Every Div B robot has an omni drive: four measured wheel speeds, standing still.
    ASSERT_TRUE(r["drive"].IsObject()) << "robot " << i;
    ASSERT_EQ(r["drive"]["wheels"].Size(), 4u);
    EXPECT_NEAR(r["drive"]["forward"].GetDouble(), 0.0, 1e-2);
  }
  EXPECT_EQ(state["status"]["clients"].GetInt(), 1);

  // Pause: the kernel's clock control sees it.
  page.Send(R"({"cmd":"pause","id":1})");
  EXPECT_EQ(page.ReadType("ack")["id"].GetInt(), 1);
  world->ProcessEvents();
  EXPECT_TRUE(world->clock_control().paused);

  // Paused, a dragged ball moves in the world, and the page sees it without a step.
  const std::int64_t steps = world->clock().steps();
  page.Send(R"({"cmd":"move","target":"ball","x":1.0,"y":-0.5,"id":2})");
  EXPECT_EQ(page.ReadType("ack")["id"].GetInt(), 2);
  const rapidjson::Document moved = StateWhere(page, [](const rapidjson::Document& d) {
    return std::abs(d["ball"]["x"].GetDouble() - 1.0) < 1e-9;
  }, false);
  ASSERT_TRUE(moved.IsObject());
  EXPECT_NEAR(moved["ball"]["y"].GetDouble(), -0.5, 1e-9);
  EXPECT_EQ(world->GroundTruth().ball.pose.position.x(), 1.0);
  EXPECT_EQ(world->GroundTruth().ball.pose.position.y(), -0.5);
  EXPECT_EQ(world->clock().steps(), steps) << "nothing stepped";

  // A robot dragged and turned.
  page.Send(R"({"cmd":"move","target":{"team":"yellow","id":2},"x":0.5,"y":2.0,"yaw":1.0})");
  page.ReadType("ack");
  world->ProcessEvents();
  const RobotState yellow2 = world->GroundTruth().robots.at(8);
  ASSERT_EQ(yellow2.id, (RobotId{Team::kYellow, 2}));
  EXPECT_NEAR(yellow2.pose.position.x(), 0.5, 1e-9);
  EXPECT_NEAR(yellow2.pose.Yaw(), 1.0, 1e-9);

  // Step, speed and resume.
  page.Send(R"({"cmd":"step","steps":5})");
  page.ReadType("ack");
  page.Send(R"({"cmd":"speed","factor":2})");
  page.ReadType("ack");
  world->ProcessEvents();
  EXPECT_EQ(world->clock_control().pending_steps, 5);
  EXPECT_EQ(world->clock_control().speed_factor, 2.0);

  // A kick: the ball leaves at the velocity the gesture asked for.
  page.Send(R"({"cmd":"kick","vx":2.0,"vy":1.0})");
  page.ReadType("ack");
  world->Step();
  EXPECT_NEAR(world->GroundTruth().ball.twist.linear.x(), 2.0, 0.05);
  EXPECT_NEAR(world->GroundTruth().ball.twist.linear.y(), 1.0, 0.05);

  // A malformed command changes nothing and is answered with the reason.
  const auto applied = world->event_counters().applied;
  page.Send(R"({"cmd":"move","target":"ball","x":"left","y":0,"id":9})");
  const rapidjson::Document error = page.ReadType("error");
  EXPECT_EQ(error["id"].GetInt(), 9);
  EXPECT_NE(std::string(error["message"].GetString()).find("'x' must be a finite number"), std::string::npos);
  world->ProcessEvents();
  EXPECT_EQ(world->event_counters().applied, applied);
  EXPECT_NE(log_text.str().find("viewer command refused"), std::string::npos) << log_text.str();
}

// ---------------------------------------------------------------- the match

// A UDP port nobody on this machine holds now (the referee socket shares its port anyway).
std::uint16_t FreeUdpPort() {
  asio::io_context io;
  asio::ip::udp::socket s(io, asio::ip::udp::endpoint(asio::ip::udp::v4(), 0));
  return s.local_endpoint().port();
}

std::span<const std::uint8_t> Bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

// The plugin in a local-only world, listening for the referee on a test-only port of the
// league's group; the test sends as the game controller does, on loopback.
struct ViewerMatch : ViewerWorld {
  std::uint16_t referee_port = 0;
  std::unique_ptr<transport::MulticastSender> referee;

  void SetUp() override {
    referee_port = FreeUdpPort();
    transport::MulticastSender::Options o;
    o.group = "224.5.23.1";
    o.port = referee_port;
    o.interfaces = {"127.0.0.1"};
    o.local_only = true;
    o.name = "test referee";
    referee = std::make_unique<transport::MulticastSender>(o);
  }
  void BuildWithReferee(const std::string& more = "") {
    Build(R"({"port": 0, "rate": 200, "referee_port": )" + std::to_string(referee_port) + more + "}");
  }
  // Sends `message` until the page has a referee message (a datagram may be lost, even on
  // loopback); states come every 5 ms, so 20 of them is ~0.1 s per try.
  std::optional<rapidjson::Document> SendUntilShown(WsClient& page, const std::string& bytes) {
    for (int i = 0; i < 50; ++i) {
      EXPECT_TRUE(referee->Send(Bytes(bytes))) << referee->LastError();
      if (auto d = page.TryReadType("referee", 20)) return d;
    }
    return std::nullopt;
  }
};

TEST_F(ViewerMatch, APageGetsTheRefereeAsATeamDoesInSiUnits) {
  BuildWithReferee();
  WsClient page(port);
  const rapidjson::Document hello = page.ReadType("hello");
  EXPECT_EQ(std::string(hello["referee"].GetString()), "224.5.23.1:" + std::to_string(referee_port));

  // Garbage on the referee's port is counted and logged, and changes nothing.
  const std::string garbage = "not a referee message";
  ASSERT_TRUE(referee->Send(Bytes(garbage)));
  const auto shown = SendUntilShown(page, ubersim::testing::StopRefereeDatagram("ER-Force", "TIGERs", 120'000'000));
  ASSERT_TRUE(shown.has_value()) << "no referee message reached the page; log:\n" << log_text.str();
  const rapidjson::Document& d = *shown;
  EXPECT_STREQ(d["stage"].GetString(), "NORMAL_FIRST_HALF");
  EXPECT_DOUBLE_EQ(d["stage_time_left"].GetDouble(), 120.0);
  EXPECT_STREQ(d["command"].GetString(), "STOP");
  EXPECT_EQ(d["command_counter"].GetUint(), 3u);
  EXPECT_STREQ(d["next_command"].GetString(), "DIRECT_FREE_YELLOW");
  EXPECT_DOUBLE_EQ(d["designated_position"]["x"].GetDouble(), -1.2);
  EXPECT_DOUBLE_EQ(d["designated_position"]["y"].GetDouble(), 0.8);
  EXPECT_STREQ(d["yellow"]["name"].GetString(), "ER-Force");
  EXPECT_EQ(d["yellow"]["score"].GetUint(), 1u);
  EXPECT_STREQ(d["blue"]["name"].GetString(), "TIGERs");
  EXPECT_EQ(d["blue"]["yellow_cards"].GetUint(), 1u);
  EXPECT_DOUBLE_EQ(d["blue"]["yellow_card_times"][0].GetDouble(), 45.0);
  EXPECT_STREQ(d["game_event"]["type"].GetString(), "BALL_LEFT_FIELD_TOUCH_LINE");
  EXPECT_STREQ(d["game_event"]["by_team"].GetString(), "blue");
  EXPECT_NE(log_text.str().find("referee datagram ignored: not a Referee message (21 bytes)"), std::string::npos)
      << log_text.str();

  // The status says how long ago the referee spoke.
  const rapidjson::Document state = page.ReadType("state");
  ASSERT_TRUE(state["status"]["referee_age"].IsNumber());
  EXPECT_LT(state["status"]["referee_age"].GetDouble(), 5.0);

  // A page that connects now gets the match at once, right after the hello.
  WsClient late(port);
  EXPECT_STREQ(Parse(late.Read())["type"].GetString(), "hello");
  const rapidjson::Document caught_up = Parse(late.Read());
  EXPECT_STREQ(caught_up["type"].GetString(), "referee");
  EXPECT_STREQ(caught_up["yellow"]["name"].GetString(), "ER-Force");
}

TEST_F(ViewerMatch, ABurstOfRefereeMessagesReachesThePageRateLimitedNewestLast) {
  BuildWithReferee();
  WsClient page(port);
  page.ReadType("hello");
  ASSERT_TRUE(SendUntilShown(page, ubersim::testing::StopRefereeDatagram("Yellow", "Blue", 120'000'000)).has_value())
      << log_text.str();
  // 30 changes within a few milliseconds: the page gets a few, the last of them the newest.
  for (int i = 1; i <= 30; ++i) {
    const std::string bytes = ubersim::testing::StopRefereeDatagram("Yellow", "Blue", 120'000'000 - i * 25'000);
    ASSERT_TRUE(referee->Send(Bytes(bytes)));
  }
  const double newest = (120'000'000 - 30 * 25'000) * 1e-6;
  int referees = 0;
  bool seen_newest = false;
  for (int i = 0; i < 1000 && !seen_newest; ++i) {  // ~5 s of states
    const rapidjson::Document d = Parse(page.Read());
    if (std::string(d["type"].GetString()) != "referee") continue;
    ++referees;
    seen_newest = std::abs(d["stage_time_left"].GetDouble() - newest) < 1e-9;
  }
  EXPECT_TRUE(seen_newest);
  EXPECT_LE(referees, 5) << "at most one per 100 ms (and the newest after the burst)";
}

TEST_F(ViewerMatch, WithoutShowRefereeThereIsNoMatchAndABadGroupIsRefused) {
  BuildWithReferee(R"(, "show_referee": false)");
  WsClient page(port);
  const rapidjson::Document hello = page.ReadType("hello");
  EXPECT_TRUE(hello["referee"].IsNull());
  ASSERT_TRUE(referee->Send(Bytes(ubersim::testing::StopRefereeDatagram("Y", "B", 60'000'000))));
  EXPECT_FALSE(page.TryReadType("referee", 40).has_value());
  page.ws.close(websocket::close_code::normal);
  world.reset();

  const kernel::ModelLoader loader(kernel::ModelLoader::DefaultSchemaDir(),
                                   [this](PluginKind k, const std::string& id) {
                                     return registry.Find(k, id).schema_json;
                                   });
  kernel::WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml");
  model.transports.clear();
  model.transports.push_back(kernel::TransportModel{
      "viewer", ParamView::FromJson(R"({"port": 0, "referee_address": "127.0.0.1"})")});
  model.local_only = true;
  try {
    kernel::World w(model, registry, log);
    FAIL() << "a unicast referee_address was taken";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("referee_address"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not an IPv4 multicast group"), std::string::npos) << e.what();
  }
}

}  // namespace
