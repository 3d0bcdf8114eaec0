#include "hair_sim/core/util/YamlReader.hpp"

#include <gtest/gtest.h>

#include "TestUtil.hpp"

namespace hair_sim {
namespace {

YamlReader reader(const std::string& text) {
  return YamlReader::loadFile(test::writeTemp("reader.yaml", text));
}

TEST(YamlReaderTest, ReadsTypedValues) {
  const YamlReader y = reader("a: 1.5\nb: 3\nc: true\nd: name\ne: [1, 2, 3]\n");
  EXPECT_DOUBLE_EQ(y.getDouble("a", 0, 2), 1.5);
  EXPECT_EQ(y.getInt("b", 0, 5), 3);
  EXPECT_TRUE(y.getBool("c", false));
  EXPECT_EQ(y.getString("d"), "name");
  EXPECT_EQ(y.getVec3("e"), Vec3(1, 2, 3));
  EXPECT_DOUBLE_EQ(y.getDouble("missing", 0, 1, 0.25), 0.25);
}

TEST(YamlReaderTest, ErrorsNameFileKeyLineAndValue) {
  const YamlReader y = reader("a: 7.5\nb: .nan\nc: [1, 2]\nd: hello\ntypo: 1\n");
  std::string m = test::errorOf([&] { y.getDouble("a", 0, 2); });
  EXPECT_NE(m.find("reader.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("a (line 1)"), std::string::npos) << m;
  EXPECT_NE(m.find("7.5"), std::string::npos) << m;
  m = test::errorOf([&] { y.getDouble("b", 0, 2); });
  EXPECT_NE(m.find("finite"), std::string::npos) << m;
  m = test::errorOf([&] { y.getVec3("c"); });
  EXPECT_NE(m.find("3 numbers"), std::string::npos) << m;
  m = test::errorOf([&] { y.getInt("d", 0, 1); });
  EXPECT_NE(m.find("'hello'"), std::string::npos) << m;
  m = test::errorOf([&] { y.requireKeys({"a", "b", "c", "d"}); });
  EXPECT_NE(m.find("unknown key 'typo'"), std::string::npos) << m;
  m = test::errorOf([&] { y.getString("absent"); });
  EXPECT_NE(m.find("absent"), std::string::npos) << m;
}

TEST(YamlReaderTest, BadFilesAreNamed) {
  std::string m = test::errorOf([] { YamlReader::loadFile("/nonexistent/x.yaml"); });
  EXPECT_NE(m.find("/nonexistent/x.yaml"), std::string::npos);
  m = test::errorOf([] { YamlReader::loadFile(test::writeTemp("broken.yaml", "a: [1, 2\n")); });
  EXPECT_NE(m.find("syntax"), std::string::npos) << m;
  m = test::errorOf([] { YamlReader::loadFile(test::writeTemp("list.yaml", "- 1\n- 2\n")); });
  EXPECT_NE(m.find("top level"), std::string::npos) << m;
  // A directory opens, then fails to read (basic_filebuf::underflow without a path, before).
  const std::string file = test::writeTemp("in_a_dir.yaml", "a: 1\n");
  const std::string dir = file.substr(0, file.find_last_of('/'));
  m = test::errorOf([&] { YamlReader::loadFile(dir); });
  EXPECT_EQ(m, dir + ": is a directory, not a file");
  // Nested 1,500 deep: yaml-cpp's own message was "bad file".
  const std::string deep =
      test::writeTemp("deep.yaml", "a: " + std::string(1500, '[') + std::string(1500, ']') + "\n");
  m = test::errorOf([&] { YamlReader::loadFile(deep); });
  EXPECT_EQ(m, deep +
                   " (line 1): YAML nested too deep for the parser (sequences and maps within each other; "
                   "hair_sim's files need 5 levels at most)");
}

TEST(YamlReaderTest, AKeyGivenTwiceIsNamedWithBothLines) {
  // yaml-cpp keeps both and a lookup finds the first: the second, a likely edit, was ignored before.
  const YamlReader y = reader("a: 1\nb: 2\na: 3\n");
  const std::string m = test::errorOf([&] { y.requireKeys({"a", "b"}); });
  EXPECT_NE(m.find("reader.yaml: a (line 3): key 'a' given twice (first on line 1)"), std::string::npos) << m;
  EXPECT_NO_THROW(reader("a: 1\nb: 2\n").requireKeys({"a", "b"}));
}

TEST(YamlReaderTest, FormatDoubleRoundTrips) {
  for (double v : {0.1, 1.0 / 3.0, 1e-300, -2.5e17, 0.004166666666666667})
    EXPECT_EQ(std::stod(formatDouble(v)), v);
}

}  // namespace
}  // namespace hair_sim
