#include "hpa/models/param_table.h"

#include <gtest/gtest.h>

#include "hpa/models/input_error.h"
#include "hpa/models/param_yaml.h"

namespace hpa {
namespace {

struct Toy {
  bool enabled = false;
  double gain = 0.5;
  int steps = 2;
  Eigen::Vector3d axes{1, 2, 3};
};

const ParamTable<Toy>& ToyTable() {
  static const ParamTable<Toy> t{"toy",
                                 "a config for the test",
                                 {{"enabled", "", 0, 0, "switch", &Toy::enabled},
                                  {"gain", "-", 0.0, 1.0, "a gain", &Toy::gain},
                                  {"steps", "-", 0, 10, "a count", &Toy::steps},
                                  {"axes", "m", -5.0, 5.0, "per axis", &Toy::axes}}};
  return t;
}

Toy Read(const std::string& text) {
  Toy toy;
  ReadParamTable(YamlMap(LoadYamlText(text, "toy.yaml"), "toy.yaml", "toy"), ToyTable(), &toy);
  return toy;
}

TEST(ParamTableTest, ReadsPresentKeysAndKeepsTheRest) {
  const Toy a = Read("{gain: 0.25, axes: [0, -1, 4]}");
  EXPECT_FALSE(a.enabled);
  EXPECT_EQ(a.gain, 0.25);
  EXPECT_EQ(a.steps, 2);
  EXPECT_EQ(a.axes, Eigen::Vector3d(0, -1, 4));
  const Toy b = Read("{enabled: true, steps: 7}");
  EXPECT_TRUE(b.enabled);
  EXPECT_EQ(b.steps, 7);
  EXPECT_EQ(b.gain, 0.5);
}

TEST(ParamTableTest, OutOfRangeWrongSizeAndUnknownKeysAreNamed) {
  const auto message = [](const std::string& text) {
    try {
      Read(text);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("{gain: 1.5}").find("toy.gain"), std::string::npos);
  EXPECT_NE(message("{steps: 2.5}").find("toy.steps"), std::string::npos);
  EXPECT_NE(message("{axes: [1, 2]}").find("toy.axes"), std::string::npos);
  const std::string unknown = message("{gian: 0.1}");
  EXPECT_NE(unknown.find("toy.gian"), std::string::npos);
  EXPECT_NE(unknown.find("valid keys here: axes, enabled, gain, steps"), std::string::npos)
      << unknown;
}

TEST(ParamTableTest, RangeCheckAndMarkdownComeFromTheSameDeclaration) {
  EXPECT_NO_THROW(CheckParamValue(ToyTable(), "toy.", "gain", 1.0));
  EXPECT_THROW(CheckParamValue(ToyTable(), "toy.", "gain", 1.01), std::invalid_argument);
  EXPECT_THROW(CheckParamValue(ToyTable(), "toy.", "gain", NAN), std::invalid_argument);
  EXPECT_THROW(CheckParamValue(ToyTable(), "toy.", "gian", 0.1), std::invalid_argument);
  const std::string md = ParamTableMarkdown(ToyTable(), Toy{}, "toy.", "default");
  EXPECT_NE(md.find("| `toy.gain` | - | 0 to 1 | 0.5 | a gain |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `toy.enabled` |  | true / false | false | switch |"), std::string::npos);
  EXPECT_NE(md.find("| `toy.axes` | m | -5 to 5 | [1, 2, 3] | per axis |"), std::string::npos);
}

}  // namespace
}  // namespace hpa
