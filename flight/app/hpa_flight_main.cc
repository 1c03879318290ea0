// hpa-flight: the project's own flight stack (payload detector, estimator, any registered
// controller) as a separate process speaking the lockstep protocol (docs/protocol.md). The
// simulator starts it (`hpa run --flight-stack "hpa-flight"`) with HPA_FLIGHT_SOCKET set; it
// connects, builds the flight stack from the hello and answers every tick until the finish. With
// --own-rate-loop it also runs the vehicle's rate loop (the autopilot the hello's rate_loop names)
// and answers each rate_tick with the rotor speed commands. Greeted by a team_hello, it flies the
// vehicles of a team it names (docs/protocol.md, "Teams").

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "hpa/autopilot/autopilot.h"
#include "hpa/controller/reference_spec.h"
#include "hpa/controller/team_controller.h"
#include "hpa/flight/protocol.h"
#include "hpa/flight/team_protocol.h"

namespace {

using hpa::flight::Channel;
using hpa::flight::MessageType;
using hpa::flight::ProtocolError;

// The simulator's shared-memory ring of rendered frames, mapped read-only.
class FrameRing {
 public:
  void Map(const nlohmann::json& camera) {
    if (camera.is_null()) return;
    const std::string name = camera.at("ring").get<std::string>();
    slots_ = camera.at("slots").get<int>();
    width_ = camera.at("width_px").get<int>();
    height_ = camera.at("height_px").get<int>();
    slot_bytes_ = camera.at("slot_bytes").get<size_t>();
    if (slot_bytes_ < static_cast<size_t>(width_) * height_ * 3) {
      throw ProtocolError("frame ring slots of " + std::to_string(slot_bytes_) +
                          " bytes cannot hold a " + std::to_string(width_) + " x " +
                          std::to_string(height_) + " BGR frame");
    }
    const int fd = ::shm_open(name.c_str(), O_RDONLY, 0);
    if (fd < 0) throw ProtocolError("cannot open the frame ring " + name);
    bytes_ = slot_bytes_ * static_cast<size_t>(slots_);
    void* p = ::mmap(nullptr, bytes_, PROT_READ, MAP_SHARED, fd, 0);
    ::close(fd);
    if (p == MAP_FAILED) throw ProtocolError("cannot map the frame ring " + name);
    base_ = static_cast<uint8_t*>(p);
  }
  ~FrameRing() {
    if (base_ != nullptr) ::munmap(base_, bytes_);
  }
  // points each frame's image at its slot
  void Attach(std::vector<hpa::flight::CameraFrame>* frames) const {
    for (hpa::flight::CameraFrame& f : *frames) {
      if (f.region.area() > 0) f.region_bgr = Slot(f.region_slot);
      f.whole_bgr = Slot(f.whole_slot);
    }
  }
  // points a frame being captured at what of it is read out so far (a slot of -1: not yet)
  void AttachCaptured(hpa::flight::CameraFrame* f) const {
    if (f->region.area() > 0 && f->region_slot >= 0) f->region_bgr = Slot(f->region_slot);
    if (f->whole_slot >= 0) f->whole_bgr = Slot(f->whole_slot);
  }

 private:
  cv::Mat Slot(int slot) const {
    if (base_ == nullptr || slot < 0 || slot >= slots_) {
      throw ProtocolError("a frame in slot " + std::to_string(slot) + " of a ring of " +
                          std::to_string(slots_));
    }
    return cv::Mat(height_, width_, CV_8UC3, base_ + slot_bytes_ * static_cast<size_t>(slot));
  }
  uint8_t* base_ = nullptr;
  size_t bytes_ = 0, slot_bytes_ = 0;
  int slots_ = 0, width_ = 0, height_ = 0;
};

// The answer to a detect: the region to read out first, the whole frame when the region cannot
// decide (or there is none), then the detection.
hpa::flight::DetectReply AnswerDetect(const hpa::flight::FlightStack& stack,
                                      const hpa::flight::CameraFrame& frame) {
  hpa::flight::DetectReply reply;
  const bool region_read = frame.region.area() > 0 && frame.region_slot >= 0;
  if (!region_read && frame.whole_slot < 0) {
    reply.camera_roi = stack.CameraRegion();
    reply.region_wanted = reply.camera_roi.area() > 0;
    reply.whole_wanted = !reply.region_wanted;
    return reply;
  }
  if (std::optional<hpa::PayloadDetection> d = stack.DetectCaptured(frame)) {
    reply.has_detection = true;
    reply.detection = *d;
  } else {
    reply.whole_wanted = true;
  }
  return reply;
}

// A team's stack (docs/protocol.md, "Teams"): each vehicle of the team_hello flies its team
// controller (the hello's, or `controller`) on the payload reference the hello describes, and
// each team_tick's views are answered in their order, each update timed as in process.
int ServeTeam(Channel& channel, const std::vector<uint8_t>& hello_bytes,
              const std::string& controller) {
  const hpa::flight::TeamHello hello = hpa::flight::ParseTeamHello(hello_bytes);
  // a stack started for one vehicle (HPA_VEHICLE) flies that one
  const char* env = std::getenv("HPA_VEHICLE");
  if (env != nullptr && *env != '\0' && hello.vehicles != std::vector<int>{std::atoi(env)}) {
    throw ProtocolError(std::string("started with HPA_VEHICLE=") + env +
                        ", but the team_hello asks for " + std::to_string(hello.vehicles.size()) +
                        " vehicle(s) from " + std::to_string(hello.vehicles.front()));
  }
  const std::string type = controller.empty() ? hello.controller : controller;
  const std::shared_ptr<const hpa::Reference> reference =
      hpa::MakeReference(hello.reference, hello.team.vehicles.front().params);
  std::map<int, std::unique_ptr<hpa::TeamController>> controllers;  // by vehicle
  for (const int i : hello.vehicles) {
    try {
      controllers[i] = hpa::MakeTeamController(type, hello.team, i, reference);
    } catch (const std::invalid_argument& e) {
      throw ProtocolError(std::string("team controller: ") + e.what());
    }
  }
  channel.SendJson(MessageType::kTeamHelloAck,
                   {{"protocol_version", hpa::flight::kProtocolVersion},
                    {"name", "hpa-flight (" + type + ")"},
                    {"controller", type},
                    {"control_rate_hz", controllers.begin()->second->RateHz()},
                    {"vehicles", hello.vehicles}});
  std::vector<uint8_t> body;
  std::vector<hpa::flight::TeamVehicleReply> replies;
  while (true) {
    const MessageType type_in = channel.Receive(&body, 0.0);
    if (type_in == MessageType::kTeamTick) {
      const hpa::flight::TeamTick tick = hpa::flight::DecodeTeamTick(body);
      replies.clear();
      for (const hpa::flight::TeamVehicleView& v : tick.views) {
        const auto it = controllers.find(v.vehicle);
        if (it == controllers.end()) {
          throw ProtocolError("a team_tick view of vehicle " + std::to_string(v.vehicle) +
                              ", which this stack does not fly");
        }
        // the update's wall time, measured as the in-process team link measures it
        using Clock = std::chrono::steady_clock;
        const Clock::time_point start = Clock::now();
        hpa::flight::TeamVehicleReply& reply = replies.emplace_back();
        reply.vehicle = v.vehicle;
        reply.output = it->second->Update(v.view);
        reply.output.solve_time_ms =
            std::chrono::duration<double, std::milli>(Clock::now() - start).count();
        reply.cable_taut = it->second->CableTaut();
      }
      channel.Send(MessageType::kTeamTickReply, hpa::flight::EncodeTeamTickReply(replies));
    } else if (type_in == MessageType::kFinish) {
      channel.SendJson(MessageType::kFinishReply, nlohmann::json::object());
      return 0;
    } else {
      throw ProtocolError("unexpected " + hpa::flight::MessageTypeName(type_in) + " message");
    }
  }
}

int Serve(Channel& channel, const std::string& controller, const std::string& estimator,
          bool per_tick, bool own_rate_loop) {
  std::vector<uint8_t> hello_bytes;
  const MessageType first = channel.Receive(&hello_bytes, 60.0);
  if (first == MessageType::kTeamHello) {
    // a team's vehicles keep their rate loops in the simulator
    if (own_rate_loop) throw ProtocolError("--own-rate-loop: a team's stack owns no rate loop");
    return ServeTeam(channel, hello_bytes, controller);
  }
  if (first != MessageType::kHello) {
    throw ProtocolError("expected a hello message, got " + hpa::flight::MessageTypeName(first));
  }
  const nlohmann::json hello = nlohmann::json::parse(hello_bytes.begin(), hello_bytes.end());
  const uint32_t version = hello.at("protocol_version").get<uint32_t>();
  if (version != hpa::flight::kProtocolVersion) {
    throw ProtocolError("the simulator speaks protocol version " + std::to_string(version) +
                        ", hpa-flight version " + std::to_string(hpa::flight::kProtocolVersion));
  }
  hpa::flight::FlightConfig config = hpa::flight::ConfigFromJson(hello.at("config"));
  if (!controller.empty()) config.controller.type = controller;
  if (!estimator.empty()) config.estimator = estimator;
  hpa::flight::FlightStack stack(config);
  // the rate loop, when this stack owns it: the autopilot the simulator would run, from the
  // world profile's rate_loop section as the hello carries it
  std::unique_ptr<hpa::Autopilot> autopilot;
  if (own_rate_loop) {
    if (!hello.contains("rate_loop")) {
      throw ProtocolError("--own-rate-loop: the simulator's hello carries no rate_loop");
    }
    const hpa::flight::RateLoopConfig rate_loop =
        hpa::flight::RateLoopFromJson(hello.at("rate_loop"));
    autopilot = hpa::MakeAutopilot(config.params, rate_loop.spec, rate_loop.own_rate_hz);
  }
  FrameRing ring;
  ring.Map(hello.value("camera", nlohmann::json()));
  // named after the controller it flies: metrics.json's controller equals the in-process run's
  nlohmann::json ack = {{"protocol_version", hpa::flight::kProtocolVersion},
                        {"name", "hpa-flight (" + config.controller.type + ")"},
                        {"controller", config.controller.type},
                        {"control_rate_hz", stack.control_rate_hz()},
                        {"batched_ticks", !per_tick},
                        {"detects_at_capture", !per_tick}};
  if (own_rate_loop) ack["owns_rate_loop"] = true;
  channel.SendJson(MessageType::kHelloAck, ack);
  std::vector<uint8_t> body;
  int frames_found = 0;  // of the ticks answered by no reply yet
  while (true) {
    const MessageType type = channel.Receive(&body, 0.0);
    if (type == MessageType::kTick) {
      hpa::flight::FlightInputs in = hpa::flight::DecodeTick(body);
      ring.Attach(&in.frames);
      const hpa::flight::FlightOutputs out = stack.Step(in);
      // a tick flagged no_reply is answered by none; its frames found join the next reply
      frames_found += out.frames_detected;
      if (in.no_reply) continue;
      hpa::flight::FlightOutputs reply = out;
      reply.frames_detected = std::exchange(frames_found, 0);
      channel.Send(MessageType::kTickReply, hpa::flight::EncodeReply(reply));
    } else if (type == MessageType::kDetect) {
      hpa::flight::CameraFrame frame = hpa::flight::DecodeDetect(body);
      ring.AttachCaptured(&frame);
      channel.Send(MessageType::kDetectReply,
                   hpa::flight::EncodeDetectReply(AnswerDetect(stack, frame)));
    } else if (type == MessageType::kRateTick && autopilot) {
      const hpa::flight::RateTick tick = hpa::flight::DecodeRateTick(body);
      channel.Send(MessageType::kRateReply,
                   hpa::flight::EncodeRateReply(autopilot->Update(tick.command, tick.w_B_radps)));
    } else if (type == MessageType::kFinish) {
      hpa::flight::FlightInputs in = hpa::flight::DecodeTick(body);
      ring.Attach(&in.frames);
      const int found = stack.Finish(in) + frames_found;
      nlohmann::json health = nlohmann::json::array();
      for (const auto& [name, value] : stack.EstimatorHealth()) health.push_back({name, value});
      channel.SendJson(MessageType::kFinishReply,
                       {{"estimator", config.ground_truth ? "" : config.estimator},
                        {"estimator_health", health},
                        {"frames_detected", found}});
      return 0;
    } else {
      throw ProtocolError("unexpected " + hpa::flight::MessageTypeName(type) + " message");
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "hpa-flight: the project's flight stack (payload detector, estimator, registered "
      "controller) as its own process, speaking the lockstep protocol of docs/protocol.md. "
      "`hpa run --flight-stack hpa-flight SCENARIO` starts it with HPA_FLIGHT_SOCKET set; it "
      "builds the stack the simulator's hello describes and answers each tick.",
      "hpa-flight"};
  std::string socket_path;
  std::string controller, estimator;
  app.add_option("--socket", socket_path,
                 "the simulator's Unix socket (default: $HPA_FLIGHT_SOCKET)");
  app.add_option("--controller", controller,
                 "fly this registered controller instead of the scenario's");
  app.add_option("--estimator", estimator,
                 "use this registered estimator instead of the scenario's");
  bool per_tick = false;
  app.add_flag("--per-tick", per_tick,
               "answer every tick and receive whole frames, as a stack that declares neither "
               "batched_ticks nor detects_at_capture (the protocol's first behaviour)");
  bool own_rate_loop = false;
  app.add_flag("--own-rate-loop", own_rate_loop,
               "run the vehicle's rate loop here (the autopilot of the hello's rate_loop: the "
               "world profile's) and answer rate_tick messages with rotor speed commands, "
               "declaring owns_rate_loop; the simulator then runs no autopilot");
  CLI11_PARSE(app, argc, argv);
  if (socket_path.empty()) {
    const char* env = std::getenv("HPA_FLIGHT_SOCKET");
    if (env == nullptr || *env == '\0') {
      std::fprintf(stderr,
                   "hpa-flight: no socket: give --socket PATH or set HPA_FLIGHT_SOCKET (hpa run "
                   "--flight-stack sets it)\n");
      return 2;
    }
    socket_path = env;
  }
  std::unique_ptr<Channel> channel;
  try {
    channel = std::make_unique<Channel>(hpa::flight::ConnectUnix(socket_path));
    return Serve(*channel, controller, estimator, per_tick, own_rate_loop);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hpa-flight: %s\n", e.what());
    if (channel) {
      try {
        const std::string text = std::string("hpa-flight: ") + e.what();
        channel->Send(MessageType::kError, std::vector<uint8_t>(text.begin(), text.end()));
      } catch (const std::exception&) {
        // the simulator has gone: nothing to tell
      }
    }
    return 1;
  }
}
