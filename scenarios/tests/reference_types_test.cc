// The declared payload reference types: their names and order, the keys' sizes, ranges and
// defaults being consistent, and FindReferenceKey's lookup and refusal.

#include "hpa/scenarios/reference_types.h"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "hpa/controller/reference_spec.h"

namespace hpa {
namespace {

TEST(ReferenceTypesTest, TypesInTheSchemaOrder) {
  std::vector<std::string> names;
  for (const ReferenceType& t : ReferenceTypes()) names.push_back(t.name);
  // the same names as ReferenceSpec::type accepts (controller/reference_spec.h)
  EXPECT_EQ(names, (std::vector<std::string>{"hover", "lissajous", "line", "circle", "figure_eight",
                                             "csv"}));
}

TEST(ReferenceTypesTest, EveryTypeHasItsOwnRmseWindow) {
  // only the Lissajous family ramps up: its RMSE starts at the ramp's end, every other type's at 0
  // (a CSV flies its first sample at once; it once got the Lissajous's 2 s)
  const std::map<std::string, double> expected = {{"hover", 0.0},        {"lissajous", 3.5},
                                                  {"line", 0.0},         {"circle", 3.5},
                                                  {"figure_eight", 3.5}, {"csv", 0.0}};
  ASSERT_EQ(expected.size(), ReferenceTypes().size());
  for (const ReferenceType& t : ReferenceTypes()) {
    ReferenceSpec spec;
    spec.type = t.name;
    spec.lissajous.ramp_s = 3.5;
    ASSERT_EQ(expected.count(t.name), 1u) << t.name;
    EXPECT_EQ(RmseFromS(spec), expected.at(t.name)) << t.name;
  }
}

TEST(ReferenceTypesTest, EveryKeyIsDescribedOnceWithAConsistentRange) {
  for (const ReferenceType& t : ReferenceTypes()) {
    EXPECT_FALSE(t.description.empty()) << t.name;
    EXPECT_FALSE(t.keys.empty()) << t.name;
    std::set<std::string> seen;
    for (const ReferenceKey& k : t.keys) {
      const std::string where = t.name + "." + k.key;
      EXPECT_TRUE(seen.insert(k.key).second) << "duplicate " << where;
      EXPECT_FALSE(k.meaning.empty()) << where;
      EXPECT_TRUE(k.size == 0 || k.size == 1 || k.size == 3) << where;
      if (k.size == 0) {
        // text: no unit, no range
        EXPECT_EQ(k.unit, "") << where;
        continue;
      }
      EXPECT_FALSE(k.unit.empty()) << where;
      EXPECT_LT(k.min, k.max) << where;
      if (k.fallback) {
        EXPECT_GE(*k.fallback, k.min) << where;
        EXPECT_LE(*k.fallback, k.max) << where;
      }
    }
  }
}

TEST(ReferenceTypesTest, FindReferenceKeyReturnsTheDeclaration) {
  const ReferenceKey& radius = FindReferenceKey("circle", "radius");
  EXPECT_EQ(radius.key, "radius");
  EXPECT_EQ(radius.unit, "m");
  EXPECT_EQ(radius.size, 1);
  EXPECT_FALSE(radius.fallback.has_value());  // required
  const ReferenceKey& position = FindReferenceKey("hover", "payload_position");
  EXPECT_EQ(position.size, 3);
  EXPECT_FALSE(position.fallback.has_value());
  // the Lissajous family shares period, ramp and centre, with their defaults
  for (const char* type : {"lissajous", "circle", "figure_eight"}) {
    EXPECT_EQ(FindReferenceKey(type, "period").fallback, 5.0) << type;
    EXPECT_EQ(FindReferenceKey(type, "ramp").fallback, 2.0) << type;
    EXPECT_EQ(FindReferenceKey(type, "centre").size, 3) << type;
  }
  // the same key name in two types is two declarations
  EXPECT_NE(&FindReferenceKey("circle", "height"), &FindReferenceKey("figure_eight", "height"));
}

TEST(ReferenceTypesTest, FindReferenceKeyRefusesUnknownTypesAndKeys) {
  EXPECT_THROW(FindReferenceKey("spiral", "radius"), std::out_of_range);
  // a key of another type is not this type's
  EXPECT_THROW(FindReferenceKey("hover", "radius"), std::out_of_range);
  try {
    FindReferenceKey("line", "speed");
    FAIL() << "an unknown key was found";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("line.speed"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hpa
