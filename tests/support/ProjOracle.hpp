#pragma once
// PROJ as an outside oracle for the projection and body tests: one context plus one
// operation made from a PROJ string, and helpers to spell a body's ellipsoid for PROJ.

#include <regolith/topo/Body.hpp>

#include <glm/vec3.hpp>
#include <gtest/gtest.h>
#include <proj.h>

#include <iostream>
#include <sstream>
#include <string>

namespace regolith::test {

/// One PROJ context plus one operation created from a PROJ string. Non-copyable.
class Proj {
 public:
  explicit Proj(const std::string& definition)
      : ctx_(proj_context_create()), pj_(proj_create(ctx_, definition.c_str())) {
    if (pj_ == nullptr) {
      error_ = "PROJ could not create '" + definition +
               "': " + proj_context_errno_string(ctx_, proj_context_errno(ctx_));
    }
  }
  Proj(const Proj&) = delete;
  Proj& operator=(const Proj&) = delete;
  ~Proj() {
    if (pj_ != nullptr) proj_destroy(pj_);
    proj_context_destroy(ctx_);
  }

  [[nodiscard]] bool ok() const { return pj_ != nullptr; }
  [[nodiscard]] const std::string& error() const { return error_; }
  [[nodiscard]] PJ_CONTEXT* context() const { return ctx_; }
  [[nodiscard]] PJ* get() const { return pj_; }

  /// Transforms (a, b, c) in the given direction; returns the three output components.
  [[nodiscard]] glm::dvec3 trans(PJ_DIRECTION dir, double a, double b, double c = 0.0) const {
    proj_errno_reset(pj_);
    const PJ_COORD out = proj_trans(pj_, dir, proj_coord(a, b, c, 0.0));
    return {out.v[0], out.v[1], out.v[2]};
  }
  /// proj_errno after the last trans().
  [[nodiscard]] int lastError() const { return proj_errno(pj_); }

 private:
  PJ_CONTEXT* ctx_;
  PJ* pj_;
  std::string error_;
};

/// A double with all 17 significant digits, for PROJ strings.
inline std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

/// PROJ ellipsoid parameters for a body.
inline std::string projEllipsoid(const topo::Body& body) {
  return body.isSphere() ? " +R=" + num(body.equatorialRadius())
                         : " +a=" + num(body.equatorialRadius()) + " +b=" + num(body.polarRadius());
}

/// Records and prints a measured maximum error so that the figure can be quoted.
inline void report(const std::string& key, double value) {
  std::ostringstream s;
  s.precision(3);
  s << std::scientific << value;
  ::testing::Test::RecordProperty(key, s.str());
  std::cout << "[ measured ] " << key << " = " << s.str() << '\n';
}

/// Message of the exception of type Ex thrown by f, or an empty string (and a failure).
template <class Ex, class F>
std::string messageOf(F&& f) {
  try {
    f();
  } catch (const Ex& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an exception, none was thrown";
  return {};
}

}  // namespace regolith::test
