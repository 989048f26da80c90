// SPDX-License-Identifier: Apache-2.0
// ValidateAgainstSchema: every kind of schema failure, reported at the offending value.
#include <string>

#include <gtest/gtest.h>

#include "ubersim/kernel/model.hpp"

namespace {

using ubersim::ParamView;
using ubersim::kernel::ModelError;
using ubersim::kernel::ParseYamlText;
using ubersim::kernel::ValidateAgainstSchema;

const char* const kSchema = R"({
  "$schema": "http://json-schema.org/draft-04/schema#",
  "type": "object",
  "additionalProperties": false,
  "required": ["mass", "radius"],
  "properties": {
    "mass": {"type": "number", "minimum": 0, "exclusiveMinimum": true, "maximum": 10},
    "radius": {"type": "number", "minimum": 0.01, "maximum": 1, "exclusiveMaximum": true},
    "count": {"type": "integer", "minimum": 1},
    "mode": {"type": "string", "enum": ["sap", "hash"]},
    "name": {"type": "string", "minLength": 2, "pattern": "^[a-z-]+$"},
    "gravity": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
    "flag": {"type": "boolean"},
    "body": {
      "type": "object", "additionalProperties": false, "required": ["height"],
      "properties": {"height": {"type": "number"}, "width": {"type": "number"}}
    },
    "wheels": {
      "type": "array",
      "items": {"type": "object", "additionalProperties": false,
                "properties": {"angle_deg": {"type": "number", "maximum": 360}}}
    }
  }
})";

ModelError ErrorOf(const std::string& yaml, const std::string& path = "") {
  const ParamView v(ParseYamlText(yaml, "s.yaml"), path);
  try {
    ValidateAgainstSchema(v, kSchema, "test schema");
  } catch (const ModelError& e) {
    return e;
  }
  return ModelError("", 0, 0, "", "(no error)");
}

void ExpectError(const std::string& yaml, int line, int column, const std::string& key,
                 const std::string& reason) {
  const ModelError e = ErrorOf(yaml);
  EXPECT_EQ(e.file(), "s.yaml") << yaml;
  EXPECT_EQ(e.line(), line) << yaml;
  EXPECT_EQ(e.column(), column) << yaml;
  EXPECT_EQ(e.key(), key) << yaml;
  EXPECT_EQ(e.reason(), reason) << yaml;
}

TEST(Schema, AValidTreePasses) {
  EXPECT_EQ(ErrorOf("mass: 1\nradius: 0.5\ncount: 2\nmode: sap\nname: ab-c\ngravity: [0, 0, -9.81]\n"
                    "flag: true\nbody: {height: 1}\nwheels: [{angle_deg: 30}]\n").reason(),
            "(no error)");
}

TEST(Schema, UnknownKeyNamesTheKeyAndTheAllowedOnes) {
  ExpectError("mass: 1\nradius: 0.5\nmassx: 2\n", 3, 1, "massx",
              "unknown key 'massx' (allowed: mass, radius, count, mode, name, gravity, flag, body, "
              "wheels); did you mean 'mass'?");
  ExpectError("mass: 1\nradius: 0.5\nbody:\n  height: 1\n  depth: 2\n", 5, 3, "body.depth",
              "unknown key 'depth' (allowed: height, width)");
}

TEST(Schema, WrongType) {
  ExpectError("mass: abc\nradius: 0.5\n", 1, 1, "mass", "expected a number, got string \"abc\"");
  ExpectError("mass: 1\nradius: 0.5\ncount: 1.5\n", 3, 1, "count", "expected an integer, got number 1.5");
  ExpectError("mass: 1\nradius: 0.5\nflag: 'true'\n", 3, 1, "flag", "expected true or false, got string \"true\"");
  ExpectError("mass: 1\nradius: 0.5\nbody: 3\n", 3, 1, "body",
              "expected an object (key: value mapping), got integer 3");
  ExpectError("- 1\n", 1, 1, "", "expected an object (key: value mapping), got an array");
}

TEST(Schema, OutOfRange) {
  ExpectError("mass: 0\nradius: 0.5\n", 1, 1, "mass", "value 0 must be greater than 0");
  ExpectError("mass: 10.5\nradius: 0.5\n", 1, 1, "mass", "value 10.5 is above the maximum 10");
  ExpectError("mass: 1\nradius: 0.001\n", 2, 1, "radius", "value 0.001 is below the minimum 0.01");
  ExpectError("mass: 1\nradius: 1\n", 2, 1, "radius", "value 1 must be less than 1");
  ExpectError("mass: 1\nradius: 0.5\ncount: 0\n", 3, 1, "count", "value 0 is below the minimum 1");
  ExpectError("mass: 1\nradius: 0.5\nwheels:\n  - {angle_deg: 30}\n  - {angle_deg: 400}\n", 5, 6,
              "wheels[1].angle_deg", "value 400 is above the maximum 360");
}

TEST(Schema, MissingRequiredKeyIsReportedAtTheParent) {
  ExpectError("# ball\nmass: 1\n", 2, 1, "radius", "missing required key 'radius'");
  ExpectError("mass: 1\nradius: 0.5\nbody:\n  width: 1\n", 3, 1, "body.height",
              "missing required key 'height'");
}

TEST(Schema, OtherKeywords) {
  ExpectError("mass: 1\nradius: 0.5\nmode: hashh\n", 3, 1, "mode",
              "value \"hashh\" is not allowed (allowed: sap, hash)");
  ExpectError("mass: 1\nradius: 0.5\ngravity: [0, -9.81]\n", 3, 1, "gravity",
              "expected at least 3 elements, got 2");
  ExpectError("mass: 1\nradius: 0.5\ngravity: [0, 0, -9.81, 1]\n", 3, 1, "gravity",
              "expected at most 3 elements, got 4");
  ExpectError("mass: 1\nradius: 0.5\nname: a\n", 3, 1, "name",
              "string \"a\" is shorter than 2 characters");
  ExpectError("mass: 1\nradius: 0.5\nname: A_b\n", 3, 1, "name",
              "string \"A_b\" does not match the pattern ^[a-z-]+$");
}

TEST(Schema, KeyPathsStartAtTheViewsPath) {
  const ParamView v(ParseYamlText("mass: 1\nradius: 0.5\nmasss: 1\n", "p.yaml"), "drive");
  try {
    ValidateAgainstSchema(v, kSchema, "test schema");
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.key(), "drive.masss");
    EXPECT_EQ(e.line(), 3);
  }
}

TEST(Schema, ABrokenSchemaIsReported) {
  const ParamView v(ParseYamlText("a: 1\n", "p.yaml"));
  try {
    ValidateAgainstSchema(v, "{\"type\": ", "plugin 'x' schema");
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.reason().rfind("the schema plugin 'x' schema is not valid JSON: ", 0), 0u) << e.reason();
  }
}

}  // namespace

namespace {

using ubersim::kernel::WithSchemaDefaults;

const char* const kDefaultsSchema = R"({
  "type": "object",
  "properties": {
    "speed": {"type": "number", "default": 3.5},
    "name": {"type": "string", "default": "omni"},
    "on": {"type": "boolean", "default": true},
    "count": {"type": "integer", "default": 4},
    "order": {"type": "array", "default": [3, 2, 1, 0]},
    "motor": {"type": "object", "properties": {"torque": {"type": "number", "default": 0.3},
                                               "rate": {"type": "number", "default": 150}}},
    "limits": {"type": "object", "properties": {"accel": {"type": "number", "default": 3}}},
    "wheels": {"type": "array", "items": {"type": "object", "properties": {
        "angle": {"type": "number"}, "radius": {"type": "number", "default": 0.029}}}}
  }
})";

TEST(SchemaDefaults, KeysLeftOutGetTheSchemasDefaultAndWrittenOnesStay) {
  const ParamView v(ParseYamlText("speed: 2\nmotor:\n  rate: 100\nwheels:\n  - {angle: 30}\n  - {angle: 150, radius: 0.03}\n",
                                  "d.yaml"),
                    "drive");
  const ParamView d = WithSchemaDefaults(v, kDefaultsSchema, "test");
  EXPECT_DOUBLE_EQ(d["speed"].AsDouble(), 2.0);  // written: stays
  EXPECT_EQ(d["name"].AsString(), "omni");
  EXPECT_TRUE(d["on"].AsBool());
  EXPECT_EQ(d["count"].AsInt(), 4);
  ASSERT_EQ(d["order"].Size(), 4u);
  EXPECT_EQ(d["order"].At(0).AsInt(), 3);
  EXPECT_DOUBLE_EQ(d["motor"]["torque"].AsDouble(), 0.3);  // inside an object that is there
  EXPECT_DOUBLE_EQ(d["motor"]["rate"].AsDouble(), 100.0);
  EXPECT_FALSE(d.Has("limits"));  // an object left out stays out: a plugin may ask Has()
  EXPECT_DOUBLE_EQ(d["wheels"].At(0)["radius"].AsDouble(), 0.029);  // in every array item
  EXPECT_DOUBLE_EQ(d["wheels"].At(1)["radius"].AsDouble(), 0.03);
  // A filled value is located at the object it went into (errors about it point there).
  EXPECT_EQ(d["motor"]["torque"].Node().file, "d.yaml");
  EXPECT_EQ(d["motor"]["torque"].Node().line, d["motor"].Node().line);
  EXPECT_EQ(d.Path(), "drive");
  EXPECT_FALSE(v.Has("name")) << "the original tree is left as it was";
}

TEST(SchemaDefaults, ABrokenSchemaIsReported) {
  const ParamView v(ParseYamlText("speed: 2\n", "d.yaml"));
  EXPECT_THROW(WithSchemaDefaults(v, "{not json", "test"), ModelError);
}

}  // namespace
