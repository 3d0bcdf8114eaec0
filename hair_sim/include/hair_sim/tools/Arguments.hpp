#pragma once
/// Strict parsing of the offline tools' command-line numbers (hair_sim_offline, hair_sim_generate,
/// hair_sim_soak): the whole text must be the number, with nothing before or after it (no space, no
/// "12abc"), and a number beyond its type's range is refused, never wrapped or saturated.
#include <stdexcept>
#include <string>

namespace hair_sim {

/// [-]digits that fit in a long long.
bool parseInteger(const std::string& text, long long& out);
/// Digits (no sign) that fit in an unsigned long long.
bool parseUnsigned(const std::string& text, unsigned long long& out);
/// A finite number as strtod reads it, the whole text (no inf or nan, no overflow or underflow).
bool parseReal(const std::string& text, double& out);

/// A bad command-line value: the tools exit with status 2 on it.
struct UsageError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// The value of `flag` as an integer in [min, max]; otherwise throws UsageError naming the flag and the
/// text: "--strips: 'abc' is not an integer", "--columns: 1 is below the minimum 2",
/// "--rows: 300 is above the maximum 256".
long long integerArgument(const std::string& flag, const std::string& text, long long min, long long max);
/// The same for a non-negative integer up to max ("--seed: '-1' is not a non-negative integer").
unsigned long long unsignedArgument(const std::string& flag, const std::string& text, unsigned long long max);
/// The same for a real number in [min, max]; `unit` (" m", " s") follows the bounds in the message.
double realArgument(const std::string& flag, const std::string& text, double min, double max,
                    const std::string& unit = "");

}  // namespace hair_sim
