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

// A vector whose elements have ranges of their own (PX4's per-axis gain limits).
struct PerAxis {
  Eigen::Vector3d p{0.1, 0.1, 0.1};
};

const ParamTable<PerAxis>& PerAxisTable() {
  static const ParamTable<PerAxis> t{
      "per_axis",
      "elements with ranges of their own",
      {{"p", "-", 0.0, 0.6, "roll, pitch, yaw", &PerAxis::p, "", 3,
        {{{0.01, 0.5}, {0.01, 0.6}, {0.0, 0.6}}}}}};
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

TEST(ParamTableTest, AnElementOutsideItsOwnRangeIsNamedWithItsIndex) {
  const auto read = [](const std::string& text) {
    PerAxis config;
    ReadParamTable(YamlMap(LoadYamlText(text, "a.yaml"), "a.yaml", "per_axis"), PerAxisTable(),
                   &config);
    return config;
  };
  // 0.55 is within the pitch element's range and the envelope, not the roll element's
  EXPECT_EQ(read("{p: [0.1, 0.55, 0.0]}").p, Eigen::Vector3d(0.1, 0.55, 0.0));
  try {
    read("{p: [0.55, 0.1, 0.1]}");
    FAIL() << "a roll gain past its own range was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("per_axis.p"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("element 0: expected 0.01 to 0.5, got 0.55"),
              std::string::npos)
        << e.what();
  }
  // the yaw element may be 0, the roll element may not
  EXPECT_THROW(read("{p: [0.0, 0.1, 0.1]}"), InputError);
  EXPECT_NO_THROW(read("{p: [0.1, 0.1, 0.0]}"));
  // the same ranges for a config built in code, and in the printed table
  PerAxis built;
  built.p.x() = 0.55;
  EXPECT_THROW(CheckParamTable(PerAxisTable(), "rate_loop.", built), std::invalid_argument);
  built.p = Eigen::Vector3d(0.5, 0.6, 0.6);
  EXPECT_NO_THROW(CheckParamTable(PerAxisTable(), "rate_loop.", built));
  EXPECT_NE(ParamTableMarkdown(PerAxisTable(), PerAxis{}, "", "default")
                .find("0.01 to 0.5 / 0.01 to 0.6 / 0 to 0.6"),
            std::string::npos);
}

}  // namespace
}  // namespace hpa
