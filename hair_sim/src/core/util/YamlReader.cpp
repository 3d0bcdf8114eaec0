#include "hair_sim/core/util/YamlReader.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <vector>

#include <yaml-cpp/depthguard.h>

namespace hair_sim {

YamlReader YamlReader::loadFile(const std::string& path) {
  std::error_code ignored;
  // Not through yaml-cpp: it opens a directory, fails to read it and leaks its buffer.
  if (std::filesystem::is_directory(path, ignored))
    throw std::invalid_argument(path + ": is a directory, not a file");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::invalid_argument(path + ": cannot open the file");
  } catch (const YAML::DeepRecursion& e) {  // yaml-cpp's own message is "bad file"; its depth() counts calls
    throw std::invalid_argument(
        path + " (line " + std::to_string(e.mark.line + 1) +
        "): YAML nested too deep for the parser (sequences and maps within each other; "
        "hair_sim's files need 5 levels at most)");
  } catch (const YAML::ParserException& e) {
    throw std::invalid_argument(path + " (line " + std::to_string(e.mark.line + 1) +
                                "): YAML syntax error: " + e.msg);
  } catch (const std::exception& e) {  // e.g. a file that opens but cannot be read
    throw std::invalid_argument(path + ": cannot read the file (" + e.what() + ")");
  }
  if (!root.IsMap()) {
    throw std::invalid_argument(path + ": the top level must be a map of keys, got " +
                                (root.IsNull() ? std::string("an empty document") : show(root)));
  }
  return YamlReader(root, path, "");
}

YamlReader::YamlReader(YAML::Node node, std::string file, std::string key_path)
    : node_(std::move(node)), file_(std::move(file)), key_path_(std::move(key_path)) {}

std::string YamlReader::childPath(const std::string& key) const {
  return key_path_.empty() ? key : key_path_ + "." + key;
}

std::string YamlReader::where(const YAML::Node& n, const std::string& path) const {
  std::string s = file_ + ": " + (path.empty() ? std::string("(top level)") : path);
  const YAML::Mark mark = n.Mark();
  if (mark.line >= 0) s += " (line " + std::to_string(mark.line + 1) + ")";
  return s;
}

std::string YamlReader::show(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "(nothing)";
  if (n.IsScalar()) return "'" + n.Scalar() + "'";
  YAML::Emitter out;
  out << YAML::Flow << n;
  std::string s = out.c_str();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

std::invalid_argument YamlReader::error(const std::string& key, const std::string& message) const {
  const std::string path = key.empty() ? key_path_ : childPath(key);
  const YAML::Node n = (!key.empty() && node_.IsMap() && node_[key]) ? node_[key] : node_;
  return std::invalid_argument(where(n, path) + ": " + message);
}

bool YamlReader::has(const std::string& key) const {
  return node_.IsMap() && node_[key] && !node_[key].IsNull();
}

YamlReader YamlReader::child(const std::string& key) const {
  if (!node_.IsMap()) throw error("", "expected a map, got " + show(node_));
  if (!has(key)) throw std::invalid_argument(where(node_, childPath(key)) + ": required key is missing");
  return YamlReader(node_[key], file_, childPath(key));
}

YamlReader YamlReader::at(std::size_t index) const {
  requireSequence();
  if (index >= node_.size()) throw error("", "index " + std::to_string(index) + " out of range");
  return YamlReader(node_[index], file_, key_path_ + "[" + std::to_string(index) + "]");
}

std::size_t YamlReader::size() const { return node_.size(); }

void YamlReader::requireKeys(std::initializer_list<const char*> allowed) const {
  if (!node_.IsMap()) throw error("", "expected a map, got " + show(node_));
  std::vector<YAML::Node> seen;  // yaml-cpp keeps a repeated key, and lookups find its first value
  for (const auto& kv : node_) {
    // A key must be a plain name: `{[1, 2]: x}` or `{? {a: b}}` parse as maps with a list or map key.
    if (!kv.first.IsScalar())
      throw std::invalid_argument(where(kv.first, key_path_) + ": a key must be a name, got " +
                                  show(kv.first));
    const std::string key = kv.first.Scalar();
    for (const YAML::Node& earlier : seen)
      if (earlier.Scalar() == key)
        throw std::invalid_argument(
            where(kv.first, childPath(key)) + ": key '" + key + "' given twice (first" +
            (earlier.Mark().line >= 0 ? " on line " + std::to_string(earlier.Mark().line + 1)
                                      : std::string()) +
            ")");
    seen.push_back(kv.first);
    bool ok = false;
    for (const char* a : allowed) ok = ok || key == a;
    if (!ok) {
      std::string list;
      for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      throw std::invalid_argument(where(kv.first, childPath(key)) + ": unknown key '" + key +
                                  "' (known keys: " + list + ")");
    }
  }
}

void YamlReader::requireSequence(std::size_t min_size) const {
  if (!node_.IsSequence()) throw error("", "expected a list, got " + show(node_));
  if (node_.size() < min_size)
    throw error(
        "", "expected at least " + std::to_string(min_size) + " items, got " + std::to_string(node_.size()));
}

double YamlReader::asDouble() const {
  if (!node_.IsScalar()) throw error("", "expected a number, got " + show(node_));
  double v = 0.0;
  // yaml-cpp accepts .nan/.inf; reject them and anything that is not a number.
  try {
    v = node_.as<double>();
  } catch (const YAML::Exception&) {
    throw error("", "expected a number, got " + show(node_));
  }
  if (!std::isfinite(v)) throw error("", "expected a finite number, got " + show(node_));
  return v;
}

double YamlReader::getDouble(const std::string& key, double min, double max) const {
  const double v = child(key).asDouble();
  if (v < min || v > max) {
    throw error(key, "value " + show(node_[key]) + " is outside the allowed range [" + formatDouble(min) +
                         ", " + formatDouble(max) + "]");
  }
  return v;
}

double YamlReader::getDouble(const std::string& key, double min, double max, double fallback) const {
  return has(key) ? getDouble(key, min, max) : fallback;
}

int YamlReader::getInt(const std::string& key, int min, int max) const {
  const YamlReader c = child(key);
  if (!c.node().IsScalar()) throw c.error("", "expected an integer, got " + show(c.node()));
  long long v = 0;
  try {
    v = c.node().as<long long>();
  } catch (const YAML::Exception&) {
    throw c.error("", "expected an integer, got " + show(c.node()));
  }
  if (v < min || v > max) {
    throw c.error("", "value " + show(c.node()) + " is outside the allowed range [" + std::to_string(min) +
                          ", " + std::to_string(max) + "]");
  }
  return static_cast<int>(v);
}

int YamlReader::getInt(const std::string& key, int min, int max, int fallback) const {
  return has(key) ? getInt(key, min, max) : fallback;
}

bool YamlReader::getBool(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const YamlReader c = child(key);
  try {
    return c.node().as<bool>();
  } catch (const YAML::Exception&) {
    throw c.error("", "expected true or false, got " + show(c.node()));
  }
}

std::string YamlReader::getString(const std::string& key) const {
  const YamlReader c = child(key);
  if (!c.node().IsScalar()) throw c.error("", "expected a string, got " + show(c.node()));
  return c.node().Scalar();
}

std::string YamlReader::getString(const std::string& key, const std::string& fallback) const {
  return has(key) ? getString(key) : fallback;
}

Vec3 YamlReader::asVec3() const {
  if (!node_.IsSequence() || node_.size() != 3)
    throw error("", "expected a list of 3 numbers [x, y, z], got " + show(node_));
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = at(static_cast<std::size_t>(i)).asDouble();
  return v;
}

Vec3 YamlReader::getVec3(const std::string& key) const { return child(key).asVec3(); }

Vec3 YamlReader::getVec3(const std::string& key, const Vec3& fallback) const {
  return has(key) ? getVec3(key) : fallback;
}

Vec3 YamlReader::getVec3Within(const std::string& key, double max_abs, const std::string& unit) const {
  const Vec3 v = getVec3(key);
  if (!(v.cwiseAbs().maxCoeff() <= max_abs))
    throw error(key, "every coordinate must be within +-" + formatDouble(max_abs) + " " + unit + ", got " +
                         show(node_[key]));
  return v;
}

Vec3 YamlReader::getRpy(const std::string& key) const {
  return has(key) ? getVec3Within(key, 4.0 * 3.14159265358979323846, "rad (4 pi)") : Vec3::Zero();
}

std::string formatDouble(double v) {
  char buf[40];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

}  // namespace hair_sim
