#pragma once
/// Typed, checked access to a yaml-cpp node. Every error is a std::invalid_argument whose message
/// names the file, the key path (e.g. "strips[3].rows"), the line and the bad value, so that users
/// can fix their files without reading code.
#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <string>
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {

class YamlReader {
 public:
  /// Loads a file; throws std::invalid_argument naming the file on I/O or syntax errors.
  static YamlReader loadFile(const std::string& path);
  /// Wraps an already parsed node; file is used in messages only.
  YamlReader(YAML::Node node, std::string file, std::string key_path);

  const YAML::Node& node() const { return node_; }
  const std::string& file() const { return file_; }
  const std::string& keyPath() const { return key_path_; }

  bool has(const std::string& key) const;
  /// Child map entry; throws if missing.
  YamlReader child(const std::string& key) const;
  /// Sequence element.
  YamlReader at(std::size_t index) const;
  std::size_t size() const;
  bool isSequence() const { return node_.IsSequence(); }
  bool isMap() const { return node_.IsMap(); }

  /// Throws if this map has a key outside `allowed` (catches typos such as "hinge_stifness").
  void requireKeys(std::initializer_list<const char*> allowed) const;
  /// Throws unless this node is a sequence (and, if min_size > 0, has at least min_size items).
  void requireSequence(std::size_t min_size = 0) const;

  /// Scalars of the named child. The ranges are inclusive; a non-finite number is always an error.
  double getDouble(const std::string& key, double min, double max) const;
  double getDouble(const std::string& key, double min, double max, double fallback) const;
  int getInt(const std::string& key, int min, int max) const;
  int getInt(const std::string& key, int min, int max, int fallback) const;
  bool getBool(const std::string& key, bool fallback) const;
  std::string getString(const std::string& key) const;
  std::string getString(const std::string& key, const std::string& fallback) const;
  /// [x, y, z] of finite numbers.
  Vec3 getVec3(const std::string& key) const;
  Vec3 getVec3(const std::string& key, const Vec3& fallback) const;
  /// getVec3(key) with every coordinate within [-max_abs, max_abs] (`unit` names it in the message).
  Vec3 getVec3Within(const std::string& key, double max_abs, const std::string& unit) const;
  /// A fixed orientation [roll, pitch, yaw] (rad), each within +-4 pi (beyond, a typo); zero when absent.
  Vec3 getRpy(const std::string& key) const;
  /// This node itself as [x, y, z].
  Vec3 asVec3() const;
  /// This node itself as a finite double.
  double asDouble() const;

  /// "file: key (line N): message"; the exception callers throw for semantic errors.
  std::invalid_argument error(const std::string& key, const std::string& message) const;

 private:
  std::string childPath(const std::string& key) const;
  std::string where(const YAML::Node& n, const std::string& path) const;
  static std::string show(const YAML::Node& n);

  YAML::Node node_;
  std::string file_;
  std::string key_path_;
};

/// Formats a double so that it reads back bit-identically (17 significant digits, shortest form).
std::string formatDouble(double v);

}  // namespace hair_sim
