// SPDX-License-Identifier: Apache-2.0
// ParamView: getters, paths, locations and error messages.
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "ubersim/kernel/model.hpp"
#include "ubersim/params.hpp"

namespace {

using ubersim::ParamError;
using ubersim::ParamView;

// Line and column of every key below are asserted; keep the layout.
const char* const kJson = R"({
  "name": "omni",
  "count": 4,
  "radius": 0.029,
  "enabled": true,
  "nothing": null,
  "gravity": [0, 0, -9.81],
  "drive": {
    "wheels": [{"angle_deg": 30}, {"angle_deg": 150}, {"angle_deg": "x"}]
  }
})";

std::string ErrorOf(const auto& f) {
  try {
    f();
  } catch (const ParamError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ParamView, GettersReturnTheValues) {
  const ParamView p = ParamView::FromJson(kJson, "params.json");
  EXPECT_TRUE(p.IsObject());
  EXPECT_EQ(p.Size(), 7u);
  EXPECT_EQ(p.Keys(), (std::vector<std::string>{"name", "count", "radius", "enabled", "nothing",
                                                "gravity", "drive"}));
  EXPECT_EQ(p["name"].AsString(), "omni");
  EXPECT_EQ(p["count"].AsInt(), 4);
  EXPECT_DOUBLE_EQ(p["count"].AsDouble(), 4.0);  // integers convert to real
  EXPECT_DOUBLE_EQ(p["radius"].AsDouble(), 0.029);
  EXPECT_TRUE(p["enabled"].AsBool());
  EXPECT_TRUE(p["nothing"].IsNull());
  EXPECT_TRUE(p["radius"].IsNumber());
  EXPECT_TRUE(p["count"].IsNumber());
  EXPECT_FALSE(p["name"].IsNumber());
  const ubersim::Vec3 g = p["gravity"].AsVec3();
  EXPECT_DOUBLE_EQ(g.z(), -9.81);
  EXPECT_EQ(p["gravity"].AsDoubleArray(), (std::vector<double>{0.0, 0.0, -9.81}));
  EXPECT_EQ(p["drive"]["wheels"].Size(), 3u);
  EXPECT_DOUBLE_EQ(p["drive"]["wheels"].At(1)["angle_deg"].AsDouble(), 150.0);
}

TEST(ParamView, FallbacksApplyOnlyWhenTheKeyIsAbsent) {
  const ParamView p = ParamView::FromJson(kJson);
  EXPECT_DOUBLE_EQ(p.GetDouble("radius", 1.0), 0.029);
  EXPECT_DOUBLE_EQ(p.GetDouble("missing", 1.5), 1.5);
  EXPECT_EQ(p.GetInt("count", 9), 4);
  EXPECT_EQ(p.GetInt("missing", 9), 9);
  EXPECT_FALSE(p.GetBool("missing", false));
  EXPECT_TRUE(p.GetBool("enabled", false));
  EXPECT_EQ(p.GetString("name", "x"), "omni");
  EXPECT_EQ(p.GetString("missing", "x"), "x");
  // Present but of the wrong type is an error, not the fallback.
  EXPECT_THROW(p.GetDouble("name", 1.0), ParamError);
}

TEST(ParamView, PathsAndLocationsFollowTheTree) {
  const ParamView p = ParamView::FromJson(kJson, "params.json");
  const ParamView angle = p["drive"]["wheels"].At(2)["angle_deg"];
  EXPECT_EQ(angle.Path(), "drive.wheels[2].angle_deg");
  EXPECT_EQ(angle.Location(), "params.json:9:56");       // at its key
  EXPECT_EQ(p["drive"]["wheels"].At(2).Location(), "params.json:9:55");  // at the element
  EXPECT_EQ(p["count"].Location(), "params.json:3:3");
  EXPECT_EQ(p.Location(), "params.json:1:1");
  // A view rooted elsewhere prefixes its paths.
  const ParamView rooted(std::make_shared<const ubersim::detail::ParamNode>(p["drive"].Node()), "robot.drive");
  EXPECT_EQ(rooted["wheels"].At(0).Path(), "robot.drive.wheels[0]");
}

TEST(ParamView, ErrorsSayFileLineColumnKeyAndWhy) {
  const ParamView p = ParamView::FromJson(kJson, "params.json");
  EXPECT_EQ(ErrorOf([&] { p["drive"]["wheels"].At(2)["angle_deg"].AsDouble(); }),
            "params.json:9:56: key 'drive.wheels[2].angle_deg': expected a number, got string \"x\"");
  EXPECT_EQ(ErrorOf([&] { p["radius"].AsInt(); }),
            "params.json:4:3: key 'radius': expected an integer, got number 0.029");
  EXPECT_EQ(ErrorOf([&] { p["count"].AsString(); }),
            "params.json:3:3: key 'count': expected a string, got integer 4");
  EXPECT_EQ(ErrorOf([&] { p["name"].AsBool(); }),
            "params.json:2:3: key 'name': expected true or false, got string \"omni\"");
  EXPECT_EQ(ErrorOf([&] { p["drive"]["wheel_radius"]; }),
            "params.json:8:3: key 'drive.wheel_radius': missing required key 'wheel_radius'");
  EXPECT_EQ(ErrorOf([&] { p["drive"]["wheels"].At(3); }),
            "params.json:9:5: key 'drive.wheels': index 3 is out of range (the array has 3 elements)");
  EXPECT_EQ(ErrorOf([&] { p["drive"].AsVec3(); }),
            "params.json:8:3: key 'drive': expected an array of 3 numbers [x, y, z], got an object");
  EXPECT_EQ(ErrorOf([&] { p["name"]["x"]; }),
            "params.json:2:3: key 'name': expected an object with key 'x', got string \"omni\"");
  EXPECT_EQ(std::string(p["count"].Error("must be even").what()),
            "params.json:3:3: key 'count': must be even");
  EXPECT_EQ(std::string(p.Error("whole file").what()), "params.json:1:1: whole file");
}

TEST(ParamView, DefaultViewIsAnEmptyObject) {
  const ParamView p;
  EXPECT_TRUE(p.IsObject());
  EXPECT_EQ(p.Size(), 0u);
  EXPECT_FALSE(p.Has("x"));
  EXPECT_DOUBLE_EQ(p.GetDouble("x", 2.5), 2.5);
  EXPECT_EQ(p.Location(), "<unknown>");
  EXPECT_EQ(p.ToJson(), "{}");
  EXPECT_EQ(ErrorOf([&] { p["x"]; }), "<unknown>: key 'x': missing required key 'x'");
}

TEST(ParamView, ToJsonWritesCompactJsonThatReadsBack) {
  const ParamView p = ParamView::FromJson(R"({"a": 1, "b": [2.5, "s", true, null], "c": {}})");
  EXPECT_EQ(p.ToJson(), R"({"a":1,"b":[2.5,"s",true,null],"c":{}})");
  EXPECT_EQ(ParamView::FromJson(p.ToJson()).ToJson(), p.ToJson());
  EXPECT_EQ(p["b"].ToJson(), R"([2.5,"s",true,null])");
}

TEST(ParamView, FromJsonRejectsBadTextWithItsLocation) {
  EXPECT_EQ(ErrorOf([] { ParamView::FromJson("{\n  \"a\": 1,\n  \"b\": }", "bad.json"); }),
            "bad.json:3:8: invalid JSON: Invalid value.");
  EXPECT_EQ(ErrorOf([] { ParamView::FromJson("{\"a\": 1,\n \"a\": 2}", "dup.json"); }),
            "dup.json:2:2: duplicate key 'a' (first at line 1)");
  EXPECT_EQ(ErrorOf([] { ParamView::FromJson("{} {}", "two.json"); }),
            "two.json:1:4: invalid JSON: The document root must not be followed by other values.");
  EXPECT_EQ(ErrorOf([] { ParamView::FromJson("[1e999]", "big.json"); }),
            "big.json:1:2: invalid JSON: Number too big to be stored in double.");
}

TEST(ParamView, ReadsTheYamlTreeWithItsLocations) {
  const ParamView p(ubersim::kernel::ParseYamlText("drive:\n  plugin: omni\n  wheels:\n    - {angle_deg: 30}\n", "r.yaml"));
  EXPECT_EQ(p["drive"]["wheels"].At(0)["angle_deg"].Location(), "r.yaml:4:8");
  EXPECT_EQ(ErrorOf([&] { p["drive"]["plugin"].AsDouble(); }),
            "r.yaml:2:3: key 'drive.plugin': expected a number, got string \"omni\"");
}

}  // namespace
