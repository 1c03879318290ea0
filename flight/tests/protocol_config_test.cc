// The flight configuration's params and controller block through the protocol's JSON: every
// field their tables declare goes through, by construction, and a value outside its declared
// range is refused.

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <variant>

#include "hpa/controller/controller_registry.h"
#include "hpa/flight/protocol.h"
#include "hpa/models/params.h"

namespace hpa::flight {
namespace {

// Sets every declared field of `p` to a value of its own inside its range (the k-th field at
// the k-th of 97 steps through the range), so that a field lost or swapped on the way shows.
template <class C>
void SetEveryField(const std::vector<ParamTable<C>>& tables, C* p) {
  int k = 0;
  for (const ParamTable<C>& table : tables) {
    for (const ParamDecl<C>& d : table.params) {
      const double value = d.min + (d.max - d.min) * (++k) / 97.0;
      std::visit(
          [&](auto member) {
            using T = std::decay_t<decltype(p->*member)>;
            if constexpr (std::is_same_v<T, bool>) {
              p->*member = k % 2 == 0;
            } else if constexpr (std::is_same_v<T, int>) {
              p->*member = static_cast<int>(value);
            } else if constexpr (std::is_same_v<T, double>) {
              p->*member = value;
            } else {
              auto& m = p->*member;
              for (Eigen::Index i = 0; i < m.size(); ++i) {
                const auto [min, max] = ElementRange(d, static_cast<size_t>(i));
                m.data()[i] = min + (max - min) * (k + 0.1 * i) / 97.0;
              }
            }
          },
          d.member);
    }
  }
}

TEST(ProtocolConfigTest, EveryDeclaredParamRoundTripsThroughJson) {
  FlightConfig c;
  SetEveryField(ParamsTables(), &c.params);
  const nlohmann::json json = ConfigToJson(c);
  const FlightConfig back = ConfigFromJson(nlohmann::json::parse(json.dump()));
  int fields = 0;
  std::set<std::string> names;
  for (const ParamTable<Params>& table : ParamsTables()) {
    for (const ParamDecl<Params>& d : table.params) {
      ++fields;
      const std::string name = d.wire_key.empty() ? d.key : d.wire_key;
      names.insert(name);
      std::visit([&](auto member) { EXPECT_EQ(back.params.*member, c.params.*member) << name; },
                 d.member);
    }
  }
  EXPECT_GE(fields, 22);  // every field of Params today
  // nothing on the wire that is not declared
  for (const auto& [name, value] : json.at("params").items()) {
    EXPECT_TRUE(names.count(name)) << name << " is sent but not declared in ParamsTables";
  }
  EXPECT_EQ(json.at("params").size(), names.size());
}

TEST(ProtocolConfigTest, AValueOutsideItsDeclaredRangeIsRefusedByName) {
  nlohmann::json json = ConfigToJson(FlightConfig{});
  json["params"]["cable_length_m"] = 1e300;
  try {
    ConfigFromJson(json);
    FAIL() << "a cable of 1e300 m was accepted";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("params.cable_length_m"), std::string::npos) << e.what();
  }
  json = ConfigToJson(FlightConfig{});
  json["params"]["R_BC_rowmajor"] = {1, 0, 0};
  EXPECT_THROW(ConfigFromJson(json), ProtocolError);
}

// Every setting every registered controller declares goes out and comes back with a value other
// than its default; the block sends the type and the declared settings, nothing else.
TEST(ProtocolConfigTest, EveryDeclaredControllerSettingRoundTripsThroughJson) {
  for (const ControllerRegistration& r : Controllers()) {
    FlightConfig c;
    c.controller.type = r.name;
    for (const SettingDecl& d : r.settings) {
      SettingValue other = d.default_value;
      if (std::holds_alternative<double>(other)) {
        other = 0.5 * (d.min + std::min(d.max, d.min + 1.0));  // inside the range, off the default
        if (other == d.default_value) other = d.min;
      } else if (const auto* b = std::get_if<bool>(&other)) {
        other = !*b;
      } else if (d.choices) {
        for (const std::string& name : d.choices()) {
          if (SettingValue(name) != d.default_value) other = name;
        }
      }
      ASSERT_NE(other, d.default_value) << r.name << "." << d.key;
      c.controller.settings[d.key] = other;
    }
    const nlohmann::json json = ConfigToJson(c);
    const FlightConfig back = ConfigFromJson(nlohmann::json::parse(json.dump()));
    EXPECT_EQ(back.controller.type, r.name);
    EXPECT_EQ(back.controller.settings, c.controller.settings) << r.name;
    EXPECT_EQ(json.at("controller").size(), r.settings.size() + 1) << r.name;
  }
  // a value outside its declaration is refused naming the key
  FlightConfig c;
  nlohmann::json bad = ConfigToJson(c);
  bad["controller"]["perception_weight"] = -1.0;
  try {
    ConfigFromJson(bad);
    FAIL() << "a negative perception weight was accepted";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("controller.perception_weight"), std::string::npos)
        << e.what();
  }
  bad = ConfigToJson(c);
  bad["controller"]["solver"] = "ipopt";
  EXPECT_THROW(ConfigFromJson(bad), ProtocolError);
}

}  // namespace
}  // namespace hpa::flight
