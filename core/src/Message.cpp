#include <regolith/core/Message.hpp>

#include <charconv>
#include <cmath>

namespace regolith::core {

namespace {

template <typename F>
std::string shortest(F v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return {buf, r.ptr};
}

}  // namespace

std::string number(double v) { return shortest(v); }

std::string number(float v) { return shortest(v); }

std::string format(const Message& m) {
  std::string s(m.operation);
  const auto part = [&s](std::string_view p) {
    if (p.empty()) return;
    if (!s.empty()) s += ": ";
    s += p;
  };
  part(m.file);
  if (!m.field.empty() && !m.value.empty()) {
    part(m.field);
    s += " is ";
    s += m.value;
  } else {
    part(m.field);
    part(m.value);
  }
  if (!m.expected.empty()) {
    s += s.empty() ? "expected " : ", expected ";
    s += m.expected;
  }
  return s;
}

}  // namespace regolith::core
