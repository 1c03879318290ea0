// Extending by registration: a reference type defined in this file alone (its keys, no read of
// its own, its RMSE start and its generator), registered with one call, is read from a
// scenario's YAML with its declared ranges, listed by `hpa schema references`, travels through
// the lockstep protocol's hello, and flies through the real `hpa run`.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hpa/controller/reference_types.h"
#include "hpa/flight/protocol.h"
#include "hpa/scenarios/cli.h"
#include "hpa/scenarios/scenario.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

int Hpa(std::vector<std::string> args) {
  args.insert(args.begin(), "hpa");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return HpaMain(static_cast<int>(argv.size()), argv.data());
}

// A lift: the payload held at `position`, then raised by `lift` over `duration` with the line's
// minimum-jerk time law; its RMSE counts once the lift is over.
void RegisterLiftOnce() {
  if (FindReferenceType("toy_lift") != nullptr) return;
  // the one registration call a new reference type needs
  RegisterReferenceType(
      {"toy_lift",
       "the payload raised by `lift` over `duration` from `position` (test)",
       {{"position", "m", 3, -10, 10, std::nullopt, "where the lift starts (world)"},
        {"lift", "m", 1, 0.0, 1.0, 0.2, "how far up"},
        {"duration", "s", 1, 0.5, 10, 1.5, "how long the lift takes"}},
       nullptr,  // no read of its own: the spec keeps the values as read
       [](const ReferenceSpec& spec) { return spec.values.at("duration")[0]; },
       [](const ReferenceSpec& spec, const Params& params) {
         const std::vector<double>& p = spec.values.at("position");
         const Eigen::Vector3d start(p[0], p[1], p[2]);
         return MakeLineReference(params, start,
                                  start + Eigen::Vector3d(0, 0, spec.values.at("lift")[0]),
                                  spec.values.at("duration")[0]);
       }});
}

std::string Scenario(const std::string& lift) {
  return "name: lifted\nduration: 3.0\nworld: {profile: ideal}\n"
         "controller: {type: geometric}\n"
         "estimation: {ground_truth: true, camera: analytic}\n"
         "reference: {type: toy_lift, position: [0, 0, 0.7], lift: " +
         lift + "}\nexpect: {crashed: false}\n";
}

TEST(ToyReferenceTypeTest, ARegisteredTypeIsReadFromItsKeyTable) {
  RegisterLiftOnce();
  const hpa::Scenario s = LoadScenarioText(Scenario("0.3"), "lift.yaml");
  EXPECT_EQ(s.reference.type, "toy_lift");
  // given keys as written, the others their declared defaults
  EXPECT_EQ(s.reference.values.at("position"), (std::vector<double>{0, 0, 0.7}));
  EXPECT_EQ(s.reference.values.at("lift"), (std::vector<double>{0.3}));
  EXPECT_EQ(s.reference.values.at("duration"), (std::vector<double>{1.5}));
  EXPECT_EQ(RmseFromS(s.reference), 1.5);
  // the declared range is enforced, the error naming the key
  try {
    LoadScenarioText(Scenario("1.5"), "lift.yaml");
    FAIL() << "a lift outside its range was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("reference.lift"), std::string::npos) << e.what();
  }
  // and so is a required key
  EXPECT_ANY_THROW(LoadScenarioText(
      "name: l\nduration: 1.0\nreference: {type: toy_lift, lift: 0.3}\n", "lift.yaml"));
}

TEST(ToyReferenceTypeTest, ARegisteredTypeTravelsThroughTheProtocol) {
  RegisterLiftOnce();
  flight::FlightConfig config;
  config.reference = LoadScenarioText(Scenario("0.3"), "lift.yaml").reference;
  nlohmann::json sent = flight::ConfigToJson(config);
  EXPECT_EQ(sent["reference"]["key_values"]["lift"], nlohmann::json::array({0.3}));
  const flight::FlightConfig received = flight::ConfigFromJson(sent);
  EXPECT_EQ(received.reference.values, config.reference.values);
  EXPECT_EQ(MakeReference(received.reference, Params())->At(1.0).p_WL_W,
            MakeReference(config.reference, Params())->At(1.0).p_WL_W);
  // a value outside the declared range, or a key the type does not declare, is refused
  sent["reference"]["key_values"]["lift"] = {7.0};
  EXPECT_THROW(flight::ConfigFromJson(sent), flight::ProtocolError);
  sent["reference"]["key_values"]["lift"] = {0.3};
  sent["reference"]["key_values"]["pitch"] = {0.3};
  EXPECT_THROW(flight::ConfigFromJson(sent), flight::ProtocolError);
}

TEST(ToyReferenceTypeTest, ARegisteredTypeIsListedAndFliesThroughHpaRun) {
  RegisterLiftOnce();
  testing::internal::CaptureStdout();
  ASSERT_EQ(Hpa({"schema", "references"}), 0);
  const std::string schema = testing::internal::GetCapturedStdout();
  EXPECT_NE(schema.find("toy_lift"), std::string::npos);
  EXPECT_NE(schema.find("how long the lift takes"), std::string::npos);

  const std::string dir = TestTempDir();
  std::ofstream(dir + "lift.yaml") << Scenario("0.3");
  ASSERT_EQ(Hpa({"run", dir + "lift.yaml", "--out", dir + "out", "--quiet"}), 0);
  std::ifstream in(dir + "out/metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(in);
  EXPECT_FALSE(metrics["crashed"].get<bool>());
  // the type's own RMSE window, and the lift flown: the bound is about 10x the height error
  // measured from the lift's end on ground truth; a vehicle that held the start would be 0.3 m off
  EXPECT_EQ(metrics["payload_rmse_from_s"].get<double>(), 1.5);
  EXPECT_LT(metrics["payload_rmse_m"][2].get<double>(), 0.013);
}

}  // namespace
}  // namespace hpa
