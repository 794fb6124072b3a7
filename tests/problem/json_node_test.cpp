#include "problem/json_node.hpp"

#include <gtest/gtest.h>

namespace hbirl {
namespace {

// The message of the InputError that f throws.
template <typename F>
std::string failure_of(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// A node's path is written out only on demand (json_node.hpp): whatever the nesting, it
// must read as the chain of keys and indices that reached the value.
TEST(JsonNode, PathNamesEveryKeyAndIndexAtAnyDepth) {
  const nlohmann::json doc = nlohmann::json::parse(R"({"a": [[[[[[7, {"b": [1, [2, "x"]]}]]]]]]})");
  const JsonNode root(doc, "");
  const JsonNode six = root.at("a")[0][0][0][0][0];  // more indices than a node holds inline
  EXPECT_EQ(six.path(), "a[0][0][0][0][0]");
  EXPECT_EQ(six[0].path(), "a[0][0][0][0][0][0]");
  const JsonNode deep = six[1].at("b")[1][1];
  EXPECT_EQ(deep.path(), "a[0][0][0][0][0][1].b[1][1]");
  EXPECT_EQ(deep.as_string(), "x");
  EXPECT_EQ(six[0].as_int(0, 10), 7);
  // Failures name the path, and say what was expected and found.
  EXPECT_EQ(failure_of([&] { six[0].as_int(0, 5); }), "a[0][0][0][0][0][0]: expected an integer in [0, 5], got 7");
  EXPECT_EQ(failure_of([&] { deep.as_int(0, 5); }),
            "a[0][0][0][0][0][1].b[1][1]: expected an integer in [0, 5], got the string \"x\"");
  EXPECT_EQ(failure_of([&] { six[1].at("c"); }), "a[0][0][0][0][0][1].c: missing");
  EXPECT_EQ(failure_of([&] { root.at("a")[0][0][0][0].as_number(); }),
            "a[0][0][0][0]: expected a number, got an array of 1");
}

TEST(JsonNode, UnknownKeysAreNamedWithTheirPath) {
  const nlohmann::json doc = nlohmann::json::parse(R"({"list": [{"stpes": 1, "_note": 2}]})");
  const JsonNode root(doc, "");
  std::vector<std::string> warnings;
  root.at("list")[0].check_keys({"steps"}, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], "list[0].stpes: unknown key, ignored (did you mean \"steps\"?)");
}

}  // namespace
}  // namespace hbirl
