#include "format.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace occseg::cli {

std::string fixed(double v, int digits) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << (std::fabs(v) < 0.5 * std::pow(10.0, -digits) ? 0.0 : v);
  return o.str();
}

std::string percent(double share) { return fixed(100 * share, 2) + " %"; }

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace occseg::cli
