// Numbers as the tool prints them (summaries, reports, tables), and the step timer behind the
// times it prints.
#pragma once
#include <chrono>
#include <string>

namespace occseg::cli {

// v with `digits` decimals; a value that rounds to zero prints as 0, never as -0.
std::string fixed(double v, int digits);
// A share (0..1) as a percentage with two decimals and the sign: "12.34 %".
std::string percent(double share);
// Seconds from t until now (steady clock).
double seconds_since(std::chrono::steady_clock::time_point t);

}  // namespace occseg::cli
