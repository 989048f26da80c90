// SPDX-License-Identifier: Apache-2.0
// YAML -> located tree: scalar typing, locations, and the errors of the parser stage.
#include <string>

#include <gtest/gtest.h>

#include "test_files.hpp"
#include "ubersim/kernel/model.hpp"

namespace {

using ubersim::ParamView;
using ubersim::detail::ParamNode;
using ubersim::kernel::ModelError;
using ubersim::kernel::ParseYamlFile;
using ubersim::kernel::ParseYamlText;
using Kind = ParamNode::Kind;

ModelError ErrorOf(const std::string& text, const std::string& file = "t.yaml") {
  try {
    ParseYamlText(text, file);
  } catch (const ModelError& e) {
    return e;
  }
  return ModelError("", 0, 0, "", "(no error)");
}

TEST(Yaml, ScalarsAreTypedByTheCoreSchema) {
  const ParamView p(ParseYamlText(
      "quoted: \"1\"\nsingle: '2.5'\nint: 1\nneg: -42\nplus: +7\nreal: 1.5\nexp: 1.0e-7\n"
      "dot: .5\nyes: true\nno: false\nnull1: null\nnull2: ~\nempty:\nword: hello\n"
      "onoff: on\nhexlike: 0x10\ntagged: !!str 3\nblock: |\n  text\nbig: 123456789012345678901\n",
      "t.yaml"));
  EXPECT_TRUE(p["quoted"].IsString());
  EXPECT_EQ(p["quoted"].AsString(), "1");
  EXPECT_TRUE(p["single"].IsString());
  EXPECT_EQ(p["int"].Node().kind, Kind::kInt);
  EXPECT_EQ(p["int"].AsInt(), 1);
  EXPECT_EQ(p["neg"].AsInt(), -42);
  EXPECT_EQ(p["plus"].AsInt(), 7);
  EXPECT_EQ(p["real"].Node().kind, Kind::kDouble);
  EXPECT_DOUBLE_EQ(p["real"].AsDouble(), 1.5);
  EXPECT_DOUBLE_EQ(p["exp"].AsDouble(), 1e-7);
  EXPECT_DOUBLE_EQ(p["dot"].AsDouble(), 0.5);
  EXPECT_TRUE(p["yes"].IsBool());
  EXPECT_TRUE(p["yes"].AsBool());
  EXPECT_FALSE(p["no"].AsBool());
  EXPECT_TRUE(p["null1"].IsNull());
  EXPECT_TRUE(p["null2"].IsNull());
  EXPECT_TRUE(p["empty"].IsNull());
  EXPECT_EQ(p["word"].AsString(), "hello");
  EXPECT_EQ(p["onoff"].AsString(), "on");      // YAML 1.2: not a bool
  EXPECT_EQ(p["hexlike"].AsString(), "0x10");  // only decimal numbers
  EXPECT_EQ(p["tagged"].AsString(), "3");
  EXPECT_EQ(p["block"].AsString(), "text\n");
  EXPECT_EQ(p["big"].Node().kind, Kind::kDouble);  // too large for int64
  EXPECT_DOUBLE_EQ(p["big"].AsDouble(), 123456789012345678901.0);
}

TEST(Yaml, MembersAreLocatedAtTheirKeysAndElementsAtThemselves) {
  const ParamView p(ParseYamlText("# comment\nkind: robot\nbody:\n  mass: 2.3\nlist:\n  - 1\n  -   {a: 2}\n", "r.yaml"));
  EXPECT_EQ(p["kind"].Location(), "r.yaml:2:1");
  EXPECT_EQ(p["body"].Location(), "r.yaml:3:1");
  EXPECT_EQ(p["body"]["mass"].Location(), "r.yaml:4:3");
  EXPECT_EQ(p["list"].At(0).Location(), "r.yaml:6:5");
  EXPECT_EQ(p["list"].At(1).Location(), "r.yaml:7:7");
  EXPECT_EQ(p["list"].At(1)["a"].Location(), "r.yaml:7:8");
  EXPECT_EQ(p["body"]["mass"].Node().file, "r.yaml");
}

TEST(Yaml, NonFiniteNumbersAreRejected) {
  const ModelError inf = ErrorOf("kind: ball\nmass: .inf\n");
  EXPECT_EQ(inf.file(), "t.yaml");
  EXPECT_EQ(inf.line(), 2);
  EXPECT_EQ(inf.column(), 1);
  EXPECT_EQ(inf.key(), "mass");
  EXPECT_EQ(inf.reason(), "'.inf' is not allowed: numbers must be finite");
  const ModelError nan = ErrorOf("a:\n  b: [1, .NaN]\n");
  EXPECT_EQ(nan.line(), 2);
  EXPECT_EQ(nan.column(), 10);
  EXPECT_EQ(nan.key(), "a.b[1]");
  const ModelError neg = ErrorOf("x: -.Inf\n");
  EXPECT_EQ(neg.key(), "x");
  const ModelError huge = ErrorOf("x: 1e999\n");
  EXPECT_EQ(huge.reason(), "number 1e999 is out of range: numbers must be finite");
  // Quoted, they are just strings.
  EXPECT_EQ(ParamView(ParseYamlText("x: '.inf'\n", "t.yaml"))["x"].AsString(), ".inf");
}

TEST(Yaml, DuplicateKeysAreAnError) {
  const ModelError e = ErrorOf("kind: ball\nbody:\n  mass: 1\n  radius: 2\n  mass: 3\n");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.column(), 3);
  EXPECT_EQ(e.key(), "body.mass");
  EXPECT_EQ(e.reason(), "duplicate key 'mass' (first at line 3)");
  EXPECT_EQ(std::string(e.what()), "t.yaml:5:3: key 'body.mass': duplicate key 'mass' (first at line 3)");
}

TEST(Yaml, SyntaxErrorsSayWhere) {
  const ModelError e = ErrorOf("kind: ball\nradius: 0.0215\n  mass: 0.046\n", "s.yaml");
  EXPECT_EQ(e.file(), "s.yaml");
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.column(), 7);
  EXPECT_EQ(e.key(), "");
  EXPECT_EQ(e.reason(), "YAML syntax error: illegal map value");
  EXPECT_EQ(std::string(e.what()), "s.yaml:3:7: YAML syntax error: illegal map value");
  const ModelError flow = ErrorOf("a: [1, 2\nb: 3\n", "s.yaml");
  EXPECT_EQ(flow.line(), 2);
  EXPECT_EQ(flow.reason(), "YAML syntax error: end of sequence flow not found");
  const ModelError two = ErrorOf("a: 1\n---\nb: 2\n", "s.yaml");
  EXPECT_EQ(two.line(), 2);  // its "---"
  EXPECT_EQ(two.reason(), "a model file holds one YAML document; a second one starts here");
}

TEST(Yaml, AStrayCommaIsAnErrorNotAnEndlessLoop) {
  // yaml-cpp 0.7 leaves a ',' after a document's node unread; its LoadAll then made empty
  // documents until memory ran out (found by fuzz.model_loader).
  const ModelError bare = ErrorOf(",", "c.yaml");
  EXPECT_EQ(bare.line(), 1);
  EXPECT_EQ(bare.column(), 1);
  EXPECT_EQ(bare.reason(), "YAML syntax error: unexpected ','");
  const ModelError after_map = ErrorOf("{a: 1}\n,\n", "c.yaml");
  EXPECT_EQ(after_map.line(), 2);
  EXPECT_EQ(after_map.reason(), "YAML syntax error: unexpected ','");
  const ModelError tagged = ErrorOf("!!str ,", "c.yaml");
  EXPECT_EQ(tagged.reason(), "YAML syntax error: unexpected ','");
}

TEST(Yaml, EmptyTextIsANullRoot) {
  const auto root = ParseYamlText("# only a comment\n", "e.yaml");
  EXPECT_EQ(root->kind, Kind::kNull);
  EXPECT_EQ(root->line, 1);
}

TEST(Yaml, AliasesThatExpandWithoutBoundAreAnError) {
  // Eight lines that stand for 10^8 values once expanded: refused, quickly.
  std::string text = "a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n";
  for (int i = 1; i < 8; ++i) {
    const std::string prev = "*a" + std::to_string(i - 1);
    text += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [" + prev;
    for (int k = 1; k < 10; ++k) text += ", " + prev;
    text += "]\n";
  }
  const ModelError e = ErrorOf(text);
  EXPECT_EQ(e.reason(), "more than 100000 values once aliases are expanded (aliases of aliases?)");
  EXPECT_GE(e.line(), 1);
  // Aliases that stay small are fine.
  const ParamView p(ParseYamlText("base: &b {mass: 2.3}\nrobot: *b\n", "t.yaml"));
  EXPECT_EQ(p["robot"]["mass"].AsDouble(), 2.3);
}

class YamlFile : public ubersim::testing::TempDirTest {};

TEST_F(YamlFile, MissingFileSaysSoWithoutALine) {
  const auto path = dir() / "absent.yaml";
  try {
    ParseYamlFile(path);
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_EQ(e.line(), 0);
    EXPECT_EQ(e.column(), 0);
    EXPECT_EQ(e.key(), "");
    EXPECT_EQ(e.reason(), "cannot open file: No such file or directory");
    EXPECT_EQ(std::string(e.what()), path.string() + ": cannot open file: No such file or directory");
  }
  try {
    ParseYamlFile(dir());
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.reason(), "cannot open file: Is a directory");
  }
}

TEST_F(YamlFile, EndlessFileIsRefusedNotReadForever) {
  try {
    ParseYamlFile("/dev/zero");
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.file(), "/dev/zero");
    EXPECT_EQ(e.reason(), "larger than 16 MiB: not a model file");
  }
}

TEST_F(YamlFile, ReadsAFileAndNamesItInLocations) {
  const auto path = Write("ok.yaml", "kind: ball\nradius: 0.0215\n");
  const ParamView p(ParseYamlFile(path));
  EXPECT_EQ(p["radius"].Location(), path.string() + ":2:1");
}

}  // namespace
