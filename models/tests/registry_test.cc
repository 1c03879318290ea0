#include "hpa/models/registry.h"

#include <gtest/gtest.h>

#include <functional>

namespace hpa {
namespace {

struct Named {
  std::string name;
  std::function<int()> make;
};

struct Keyed {
  std::string key;
};

TEST(RegistryTest, KeepsOrderFindsByNameAndNamesTheKnownOnes) {
  Registry<Named> r("widget", {{"b", [] { return 2; }}, {"a", [] { return 1; }}});
  EXPECT_EQ(r.Names(), (std::vector<std::string>{"b", "a"}));
  ASSERT_NE(r.Find("a"), nullptr);
  EXPECT_EQ(r.Find("a")->make(), 1);
  EXPECT_EQ(r.Find("c"), nullptr);
  try {
    r.Get("c", "widget.type");
    FAIL() << "an unknown name was found";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "widget.type: expected one of b, a, got 'c'");
  }
}

TEST(RegistryTest, RefusesEmptyDuplicateAndFactorylessEntries) {
  Registry<Named> r("widget", {{"a", [] { return 1; }}});
  EXPECT_THROW(r.Add({"", [] { return 0; }}), std::invalid_argument);
  EXPECT_THROW(r.Add({"a", [] { return 0; }}), std::invalid_argument);
  EXPECT_THROW(r.Add({"b", nullptr}), std::invalid_argument);
  r.Add({"b", [] { return 2; }});
  EXPECT_EQ(r.JoinedNames(" | "), "a | b");
  EXPECT_THROW(Registry<Named>("widget", {{"x", [] { return 0; }}, {"x", [] { return 0; }}}),
               std::invalid_argument);
}

TEST(RegistryTest, EntriesNamedByKeyWork) {
  Registry<Keyed> r("expect key", {{"crashed"}, {"mode_accuracy_min"}});
  ASSERT_NE(r.Find("mode_accuracy_min"), nullptr);
  EXPECT_THROW(r.Add({"crashed"}), std::invalid_argument);
}

}  // namespace
}  // namespace hpa
