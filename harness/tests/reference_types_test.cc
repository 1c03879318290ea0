// The registered payload reference types: their names and order, the keys' sizes, ranges and
// defaults being consistent, FindReferenceKey's lookup and refusal, and every type's behaviour
// (read from a scenario block, its generator, its RMSE start, its spec through the protocol).

#include "hpa/scenarios/reference_types.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "hpa/controller/reference_spec.h"
#include "hpa/flight/protocol.h"
#include "hpa/models/data_dir.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/scenario.h"

namespace hpa {
namespace {

TEST(ReferenceTypesTest, TypesInTheSchemaOrder) {
  std::vector<std::string> names;
  for (const ReferenceType& t : ReferenceTypes()) names.push_back(t.name);
  // the built-ins, first; a test of this binary may register more after them
  names.resize(6);
  EXPECT_EQ(names, (std::vector<std::string>{"hover", "lissajous", "line", "circle", "figure_eight",
                                             "csv"}));
}

TEST(ReferenceTypesTest, EveryTypeHasItsOwnRmseWindow) {
  // only the Lissajous family ramps up: its RMSE starts at the ramp's end, every other type's at 0
  // (a CSV flies its first sample at once; it once got the Lissajous's 2 s)
  const std::map<std::string, double> expected = {{"hover", 0.0},        {"lissajous", 3.5},
                                                  {"line", 0.0},         {"circle", 3.5},
                                                  {"figure_eight", 3.5}, {"csv", 0.0}};
  for (const ReferenceType& t : ReferenceTypes()) {
    if (expected.count(t.name) == 0) continue;  // a test's type: its own test checks it
    ReferenceSpec spec;
    spec.type = t.name;
    spec.lissajous.ramp_s = 3.5;
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


// A value of `k` within its range: the default, else 1 clipped into the range (a file key: the
// shipped sample CSV).
std::vector<double> SomeValue(const ReferenceKey& k) {
  const double v = k.fallback ? *k.fallback : std::min(std::max(1.0, k.min), k.max);
  return std::vector<double>(k.size, v);
}

// Key values for every key of `t` (SomeValue each).
ReferenceKeyValues SomeValues(const ReferenceType& t) {
  ReferenceKeyValues values;
  for (const ReferenceKey& k : t.keys) {
    if (k.size == 0) {
      values.files[k.key] = DataPath("scenarios/references/figure_eight_path.csv");
    } else {
      values.numbers[k.key] = SomeValue(k);
    }
  }
  return values;
}

// Whether two references give the same points at a few times (bit for bit).
void ExpectSameReference(const Reference& a, const Reference& b, const std::string& what) {
  for (double t_s : {0.0, 0.5, 1.7, 4.0, 30.0}) {
    const ReferencePoint pa = a.At(t_s), pb = b.At(t_s);
    EXPECT_EQ(pa.p_WL_W, pb.p_WL_W) << what << " at " << t_s;
    EXPECT_EQ(pa.a_WL_W, pb.a_WL_W) << what << " at " << t_s;
    EXPECT_EQ(pa.p_WQ_W, pb.p_WQ_W) << what << " at " << t_s;
  }
}

TEST(ReferenceTypesTest, EveryTypeHasItsBehaviour) {
  for (const ReferenceType& t : ReferenceTypes()) {
    SCOPED_TRACE(t.name);
    // what the registry requires of every entry
    ASSERT_TRUE(t.make);
    ASSERT_TRUE(t.rmse_from_s);
    // its keys read into a spec of its type, which builds a finite generator
    const ReferenceSpec spec = ReadReferenceSpec(t, SomeValues(t));
    EXPECT_EQ(spec.type, t.name);
    // a type with a read of its own fills the spec's fields; one without keeps its values
    EXPECT_EQ(spec.values.empty(), static_cast<bool>(t.read));
    const std::shared_ptr<Reference> reference = MakeReference(spec, Params());
    ASSERT_NE(reference, nullptr);
    for (double t_s : {0.0, 1.0, 10.0}) {
      const ReferencePoint p = reference->At(t_s);
      EXPECT_TRUE(p.p_WL_W.allFinite() && p.v_WL_W.allFinite() && p.a_WL_W.allFinite() &&
                  p.p_WQ_W.allFinite())
          << "at " << t_s;
    }
    // its RMSE start is a time of the run
    const double from_s = RmseFromS(spec);
    EXPECT_TRUE(std::isfinite(from_s) && from_s >= 0.0) << from_s;
    // its spec through the lockstep protocol builds the same generator on the other side
    flight::FlightConfig config;
    config.reference = spec;
    const nlohmann::json sent = flight::ConfigToJson(config);
    const flight::FlightConfig received = flight::ConfigFromJson(sent);
    EXPECT_EQ(received.reference.type, t.name);
    EXPECT_EQ(RmseFromS(received.reference), from_s);
    ExpectSameReference(*reference, *MakeReference(received.reference, Params()), "received");
    // a built-in sends the protocol's fixed reference fields, no more (docs/protocol.md)
    if (t.read) {
      std::set<std::string> fields;
      for (const auto& [key, value] : sent.at("reference").items()) fields.insert(key);
      EXPECT_EQ(fields, (std::set<std::string>{"type", "payload_position_W_m", "lissajous",
                                               "line_start_W_m", "line_end_W_m",
                                               "line_duration_s", "line_start_time_s", "file",
                                               "samples_t_p_v_a"}));
    }
  }
}

TEST(ReferenceTypesTest, EveryTypeReadsItsScenarioBlockByItsKeyTable) {
  for (const ReferenceType& t : ReferenceTypes()) {
    SCOPED_TRACE(t.name);
    // the block names only the required keys: the loader fills in the declared defaults
    std::string block = "reference:\n  type: " + t.name + "\n";
    for (const ReferenceKey& k : t.keys) {
      if (k.fallback) continue;
      if (k.size == 0) {
        block += "  " + k.key + ": references/figure_eight_path.csv\n";
      } else {
        const std::vector<double> v = SomeValue(k);
        std::string value = k.size == 1 ? std::to_string(v[0]) : "[";
        for (int i = 0; k.size > 1 && i < k.size; ++i) {
          value += (i ? ", " : "") + std::to_string(v[i]) + (i + 1 == k.size ? "]" : "");
        }
        block += "  " + k.key + ": " + value + "\n";
      }
    }
    const Scenario s = LoadScenarioText("name: ref\nduration: 1.0\n" + block,
                                        DataPath("scenarios") + "/ref.yaml");
    const ReferenceSpec expected = ReadReferenceSpec(t, SomeValues(t));
    EXPECT_EQ(s.reference.type, t.name);
    EXPECT_EQ(s.reference.file, expected.file);
    EXPECT_EQ(s.reference.values, expected.values);
    EXPECT_EQ(RmseFromS(s.reference), RmseFromS(expected));
    ExpectSameReference(*MakeReference(s.reference, Params()),
                        *MakeReference(expected, Params()), "parsed");
    // a key no type declares is refused, naming it
    try {
      LoadScenarioText("name: ref\nduration: 1.0\n" + block + "  spiral_pitch: 1.0\n",
                       DataPath("scenarios") + "/ref.yaml");
      ADD_FAILURE() << "an unknown key was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("spiral_pitch"), std::string::npos) << e.what();
    }
  }
}

TEST(ReferenceTypesTest, AnUnknownTypeIsRefusedEverywhere) {
  ReferenceSpec spec;
  spec.type = "spiral";
  EXPECT_THROW(MakeReference(spec, Params()), std::invalid_argument);
  EXPECT_THROW(RmseFromS(spec), std::invalid_argument);
  EXPECT_THROW(LoadScenarioText("name: ref\nduration: 1.0\nreference: {type: spiral}\n", "r.yaml"),
               InputError);
  // a flight stack refuses a hello naming a type it does not have
  flight::FlightConfig config;
  nlohmann::json sent = flight::ConfigToJson(config);
  sent["reference"]["type"] = "spiral";
  EXPECT_THROW(flight::ConfigFromJson(sent), flight::ProtocolError);
}

}  // namespace
}  // namespace hpa
