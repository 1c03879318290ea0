// YamlMap: strict reading of scenario, sweep and params files.

#include "hpa/models/yaml_reader.h"

#include <gtest/gtest.h>

#include "hpa/models/input_error.h"

namespace hpa {
namespace {

// The InputError message of constructing a YamlMap from `text`, or "" if it is accepted.
std::string ErrorOf(const std::string& text) {
  try {
    YamlMap map(YAML::Load(text), "f.yaml", "");
    map.RejectUnknownKeys();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(YamlMapTest, DuplicateKeyIsAnErrorNamingIt) {
  const std::string error = ErrorOf("seed: 1\nduration: 2\nseed: 3\n");
  EXPECT_NE(error.find("seed"), std::string::npos) << error;
  EXPECT_NE(error.find("duplicate"), std::string::npos) << error;
}

TEST(YamlMapTest, ComplexKeysAreInputErrors) {
  EXPECT_NE(ErrorOf("? [a, b]\n: 1\n").find("plain name"), std::string::npos);
  EXPECT_NE(ErrorOf("? {a: 1}\n: 1\n").find("plain name"), std::string::npos);
}

TEST(YamlMapTest, UnknownKeyIsNamed) {
  EXPECT_NE(ErrorOf("speling: 1\n").find("speling"), std::string::npos);
}

TEST(YamlMapTest, NonFiniteNumbersAreRefused) {
  for (const char* text : {"x: .nan\n", "x: .inf\n", "x: -.inf\n"}) {
    const YamlMap map(YAML::Load(text), "f.yaml", "");
    EXPECT_THROW(map.Number("x", -1e300, 1e300), InputError) << text;
  }
}

TEST(YamlMapTest, QuotedNumbersAndBooleansAreStringsNotValues) {
  const YamlMap map(YAML::Load("seed: \"5\"\nflag: 'true'\nv: [1, '2', 3]\nok: 5\n"), "f.yaml", "");
  EXPECT_THROW(map.Number("seed", 0, 10), InputError);
  EXPECT_THROW(map.Bool("flag", false), InputError);
  EXPECT_THROW(map.Vector("v", 3, 0, 10), InputError);
  EXPECT_EQ(map.Number("ok", 0, 10), 5.0);
  // values set in code (--set, sweeps) carry no quoting
  YAML::Node node = YAML::Load("seed: 1\n");
  node["seed"] = std::string("7");
  EXPECT_EQ(YamlMap(node, "f.yaml", "").Number("seed", 0, 10), 7.0);
}

}  // namespace
}  // namespace hpa
