// EstimatorHealth: the totals over the three filters and Fields()'s names, order and values.

#include "hpa/estimator/estimator_health.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace hpa {
namespace {

// Every counter a distinct value (powers of ten per filter), so a field reading the wrong member
// or a total missing a filter shows up as a wrong number.
EstimatorHealth DistinctHealth() {
  EstimatorHealth h;
  FilterCounts* filters[] = {&h.quad_filter, &h.cable_ekf, &h.payload_tracker};
  int scale = 1;
  for (FilterCounts* f : filters) {
    f->accepted_updates = 1 * scale;
    f->rejected_updates = 2 * scale;
    f->forced_accepts = 3 * scale;
    f->non_finite = 4 * scale;
    f->too_old = 5 * scale;
    f->out_of_order = 6 * scale;
    f->last_nis = 7.5 * scale;
    scale *= 10;
  }
  h.detections_lost = 1001;
  h.detections_non_finite = 1002;
  h.thrust_commands_non_finite = 1003;
  h.slack_entries = 1004;
  h.slack_entries_by_tension = 1005;
  h.retaut_restarts = 1006;
  h.retaut_restarts_by_tension = 1008;
  h.cable_reinitialisations = 1007;
  h.health_resets.quad_non_finite = 2001;
  h.health_resets.payload_non_finite = 2002;
  h.health_resets.payload_speed = 2003;
  h.health_resets.cable_length = 2004;
  h.slack = true;
  h.filtered_cable_length_m = 0.987;
  return h;
}

TEST(EstimatorHealthTest, RejectedUpdatesSumsTheThreeFiltersRejectionsOnly) {
  // 2 + 20 + 200: each filter's rejections once, none of its other counts
  EXPECT_EQ(DistinctHealth().RejectedUpdates(), 222);
  EXPECT_EQ(EstimatorHealth{}.RejectedUpdates(), 0);
}

TEST(EstimatorHealthTest, ForcedAcceptsSumsTheThreeFiltersForcedAcceptsOnly) {
  // 3 + 30 + 300
  EXPECT_EQ(DistinctHealth().ForcedAccepts(), 333);
  EXPECT_EQ(EstimatorHealth{}.ForcedAccepts(), 0);
}

TEST(EstimatorHealthTest, FieldsAreNamedInTheDocumentedOrder) {
  std::vector<std::string> expected = {"rejected_updates", "resets"};
  for (const std::string prefix : {"quad_", "cable_", "tracker_"}) {
    for (const char* name : {"accepted_updates", "rejected_updates", "forced_accepts", "non_finite",
                             "too_old", "out_of_order", "last_nis"}) {
      expected.push_back(prefix + name);
    }
  }
  for (const char* name :
       {"detections_lost", "detections_non_finite", "thrust_commands_non_finite", "slack_entries",
        "slack_entries_by_tension", "retaut_restarts", "retaut_restarts_by_tension",
        "cable_reinitialisations", "health_resets", "health_resets_quad_non_finite",
        "health_resets_payload_non_finite", "health_resets_payload_speed",
        "health_resets_cable_length", "slack", "filtered_cable_length_m"}) {
    expected.push_back(name);
  }
  std::vector<std::string> names;
  for (const auto& field : EstimatorHealth{}.Fields()) names.push_back(field.first);
  EXPECT_EQ(names, expected);
}

TEST(EstimatorHealthTest, EachFieldCarriesItsOwnCounter) {
  const std::vector<double> expected = {222,  333,                                // totals
                                        1,    2,    3,    4,    5,    6,    7.5,  // quad_
                                        10,   20,   30,   40,   50,   60,   75,   // cable_
                                        100,  200,  300,  400,  500,  600,  750,  // tracker_
                                        1001, 1002, 1003, 1004, 1005, 1006, 1008,
                                        1007, 8010, 2001, 2002, 2003, 2004,  // health resets
                                        1.0,  // estimator's own, slack as 1
                                        0.987};
  const auto fields = DistinctHealth().Fields();
  ASSERT_EQ(fields.size(), expected.size());
  for (size_t i = 0; i < fields.size(); ++i) {
    // exact: every value is an int or a double copied without arithmetic
    EXPECT_EQ(fields[i].second, expected[i]) << fields[i].first;
  }
}

TEST(EstimatorHealthTest, SlackFieldIsZeroWhenTaut) {
  EstimatorHealth h = DistinctHealth();
  h.slack = false;
  int found = 0;
  for (const auto& [name, value] : h.Fields()) {
    if (name != "slack") continue;
    ++found;
    EXPECT_EQ(value, 0.0);
  }
  EXPECT_EQ(found, 1);
}

}  // namespace
}  // namespace hpa
