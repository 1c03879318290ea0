#pragma once
// Numbers in sweep-diff's reasons and tables: `digits` significant digits.

#include <sstream>
#include <string>

namespace hpa {

/// v with `digits` significant digits (the stream's default notation).
inline std::string Fixed(double v, int digits = 4) {
  std::ostringstream out;
  out.precision(digits);
  out << v;
  return out.str();
}

}  // namespace hpa
