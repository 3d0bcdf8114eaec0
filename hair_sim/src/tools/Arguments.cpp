#include "hair_sim/tools/Arguments.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

namespace {

bool allDigits(const std::string& text, std::size_t from) {
  if (text.size() <= from) return false;
  for (std::size_t i = from; i < text.size(); ++i)
    if (text[i] < '0' || text[i] > '9') return false;
  return true;
}

UsageError outside(const std::string& flag, const std::string& text, const std::string& min,
                   const std::string& max, const std::string& unit) {
  return UsageError(flag + ": '" + text + "' is out of range (" + min + ".." + max + unit + ")");
}

}  // namespace

bool parseInteger(const std::string& text, long long& out) {
  if (!allDigits(text, !text.empty() && text[0] == '-' ? 1 : 0)) return false;
  errno = 0;
  const long long value = std::strtoll(text.c_str(), nullptr, 10);
  if (errno == ERANGE) return false;
  out = value;
  return true;
}

bool parseUnsigned(const std::string& text, unsigned long long& out) {
  if (!allDigits(text, 0)) return false;
  errno = 0;
  const unsigned long long value = std::strtoull(text.c_str(), nullptr, 10);
  if (errno == ERANGE) return false;
  out = value;
  return true;
}

bool parseReal(const std::string& text, double& out) {
  // strtod skips leading space: refuse it here, as the trailing characters below.
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return false;
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(value)) return false;
  out = value;
  return true;
}

long long integerArgument(const std::string& flag, const std::string& text, long long min, long long max) {
  long long value = 0;
  if (!parseInteger(text, value)) {
    if (allDigits(text, !text.empty() && text[0] == '-' ? 1 : 0))  // digits beyond long long
      throw outside(flag, text, std::to_string(min), std::to_string(max), "");
    throw UsageError(flag + ": '" + text + "' is not an integer");
  }
  if (value < min) throw UsageError(flag + ": " + text + " is below the minimum " + std::to_string(min));
  if (value > max) throw UsageError(flag + ": " + text + " is above the maximum " + std::to_string(max));
  return value;
}

unsigned long long unsignedArgument(const std::string& flag, const std::string& text,
                                    unsigned long long max) {
  unsigned long long value = 0;
  if (!parseUnsigned(text, value)) {
    if (allDigits(text, 0)) throw outside(flag, text, "0", std::to_string(max), "");
    throw UsageError(flag + ": '" + text + "' is not a non-negative integer");
  }
  if (value > max) throw UsageError(flag + ": " + text + " is above the maximum " + std::to_string(max));
  return value;
}

double realArgument(const std::string& flag, const std::string& text, double min, double max,
                    const std::string& unit) {
  double value = 0.0;
  if (!parseReal(text, value)) {
    char* end = nullptr;
    errno = 0;
    const double read = std::strtod(text.c_str(), &end);
    if (!text.empty() && !std::isspace(static_cast<unsigned char>(text[0])) &&
        end == text.c_str() + text.size() && errno == ERANGE && !std::isnan(read))
      throw outside(flag, text, formatDouble(min), formatDouble(max), unit);  // 1e400, 1e-400
    throw UsageError(flag + ": '" + text + "' is not a number");
  }
  if (value < min) throw UsageError(flag + ": " + text + " is below the minimum " + formatDouble(min) + unit);
  if (value > max) throw UsageError(flag + ": " + text + " is above the maximum " + formatDouble(max) + unit);
  return value;
}

}  // namespace hair_sim
