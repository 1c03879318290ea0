// Events: the registry names the types, same-time events apply in file order.

#include <gtest/gtest.h>

#include <fstream>

#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

Scenario Load(const std::string& events) {
  const std::string path = TestTempDir() + "events.yaml";
  std::ofstream(path) << "name: ev\nduration: 0.3\ncontroller: {type: geometric}\n"
                         "estimation: {ground_truth: true, camera: analytic}\nevents:\n"
                      << events;
  return LoadScenario(path);
}

TEST(EventsTest, UnknownTypeListsTheRegisteredOnes) {
  try {
    Load("  - {at: 0.1, type: earthquake}\n");
    FAIL() << "accepted an unknown event type";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("events.0.type"), std::string::npos) << what;
    for (const EventRegistration& r : EventTypes()) {
      EXPECT_NE(what.find(r.name), std::string::npos) << r.name << ": " << what;
    }
  }
}

TEST(EventsTest, EachTypeRejectsAnotherTypesKeys) {
  EXPECT_THROW(Load("  - {at: 0.1, type: gripper_grab, force: [1, 0, 0]}\n"), InputError);
  EXPECT_THROW(Load("  - {at: 0.1, type: wind, force: [1, 0, 0], duration: 1, body: payload}\n"),
               InputError);
}

TEST(EventsTest, SameTimeEventsApplyInFileOrder) {
  // grab then release leaves the gripper open; release then grab leaves it holding
  const Params params = LoadParams(std::string(HPA_SOURCE_DIR) + "/models/params.yaml");
  const RunResult open =
      RunScenario(Load("  - {at: 0.1, type: gripper_grab}\n  - {at: 0.1, type: gripper_release}\n"),
                  params, RunOptions{});
  const RunResult held =
      RunScenario(Load("  - {at: 0.1, type: gripper_release}\n  - {at: 0.1, type: gripper_grab}\n"),
                  params, RunOptions{});
  ASSERT_FALSE(open.rows.empty());
  ASSERT_FALSE(held.rows.empty());
  EXPECT_FALSE(open.rows.back().gripper_active);
  EXPECT_TRUE(held.rows.back().gripper_active);
}

}  // namespace
}  // namespace hpa
