// The reference-type registry of the flight code: what a registration must carry, the key-value
// accessors a type's read uses, and the check a spec received over the protocol passes.

#include "hpa/controller/reference_types.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace hpa {
namespace {

// A type with every required part, named `name`.
ReferenceType Complete(const std::string& name) {
  return {name,
          "a hover at the key's position (test)",
          {{"at", "m", 3, -1, 1, std::nullopt, "where (world)"}},
          nullptr,
          [](const ReferenceSpec&) { return 0.0; },
          [](const ReferenceSpec& spec, const Params& params) {
            const std::vector<double>& p = spec.values.at("at");
            return MakeHoverReference(params, Eigen::Vector3d(p[0], p[1], p[2]));
          }};
}

TEST(ReferenceTypeRegistryTest, ARegistrationCarriesItsBehaviour) {
  ReferenceType no_make = Complete("test_no_make");
  no_make.make = nullptr;
  EXPECT_THROW(RegisterReferenceType(no_make), std::invalid_argument);
  ReferenceType no_rmse = Complete("test_no_rmse");
  no_rmse.rmse_from_s = nullptr;
  EXPECT_THROW(RegisterReferenceType(no_rmse), std::invalid_argument);
  ReferenceType two_files = Complete("test_two_files");
  two_files.keys = {{"a", "", 0, 0, 0, std::nullopt, "one file"},
                    {"b", "", 0, 0, 0, std::nullopt, "another"}};
  EXPECT_THROW(RegisterReferenceType(two_files), std::invalid_argument);
  EXPECT_THROW(RegisterReferenceType(Complete("hover")), std::invalid_argument);  // taken
  for (const char* name : {"test_no_make", "test_no_rmse", "test_two_files"}) {
    EXPECT_EQ(FindReferenceType(name), nullptr) << name;
  }
}

TEST(ReferenceTypeRegistryTest, TheFileKeyIsTheOneOfSizeZero) {
  EXPECT_EQ(FileKeyOf(*FindReferenceType("hover")), nullptr);
  ASSERT_NE(FileKeyOf(*FindReferenceType("csv")), nullptr);
  EXPECT_EQ(FileKeyOf(*FindReferenceType("csv"))->key, "file");
}

TEST(ReferenceTypeRegistryTest, KeyValuesAreReadAsDeclared) {
  ReferenceKeyValues v;
  v.numbers = {{"r", {0.5}}, {"p", {1, 2, 3}}};
  v.files = {{"file", "/tmp/x.csv"}};
  EXPECT_EQ(v.Number("r"), 0.5);
  EXPECT_EQ(v.Vector3("p"), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(v.File("file"), "/tmp/x.csv");
  EXPECT_THROW(v.Number("p"), std::out_of_range);   // a vector is not a number
  EXPECT_THROW(v.Vector3("r"), std::out_of_range);  // nor the reverse
  EXPECT_THROW(v.Number("q"), std::out_of_range);
  EXPECT_THROW(v.File("r"), std::out_of_range);
}

TEST(ReferenceTypeRegistryTest, AReceivedSpecFitsItsTypesKeyTable) {
  if (FindReferenceType("test_at") == nullptr) RegisterReferenceType(Complete("test_at"));
  ReferenceKeyValues v;
  v.numbers = {{"at", {0.1, 0.2, 0.3}}};
  ReferenceSpec spec = ReadReferenceSpec(*FindReferenceType("test_at"), v);
  EXPECT_EQ(spec.values, v.numbers);
  EXPECT_EQ(ReferenceValuesError(spec), std::nullopt);
  EXPECT_EQ(MakeReference(spec, Params())->At(0.0).p_WL_W, Eigen::Vector3d(0.1, 0.2, 0.3));
  spec.values["at"] = {0.1, 0.2, 3.0};  // outside -1 to 1
  EXPECT_NE(ReferenceValuesError(spec), std::nullopt);
  spec.values["at"] = {0.1, 0.2};  // not 3 numbers
  EXPECT_NE(ReferenceValuesError(spec), std::nullopt);
  spec.values = {};  // a required key missing
  EXPECT_NE(ReferenceValuesError(spec), std::nullopt);
  spec.values = {{"at", {0, 0, 0}}, {"pitch", {1}}};  // a key it does not declare
  EXPECT_NE(ReferenceValuesError(spec), std::nullopt);
  // a built-in keeps its values in the spec's fields, not as key values
  ReferenceSpec hover;
  EXPECT_EQ(ReferenceValuesError(hover), std::nullopt);
  hover.values = {{"payload_position", {0, 0, 1}}};
  EXPECT_NE(ReferenceValuesError(hover), std::nullopt);
  hover.type = "spiral";
  EXPECT_NE(ReferenceValuesError(hover), std::nullopt);
}

}  // namespace
}  // namespace hpa
