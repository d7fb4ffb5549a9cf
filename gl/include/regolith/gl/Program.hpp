#pragma once
/// \file
/// A linked GLSL program.

#include <regolith/gl/GlObjects.hpp>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace regolith::gl {

/// The vertex shader of a full-screen pass: one triangle covering the viewport, at clip
/// depth 0, made from gl_VertexID alone (draw 3 vertices with any vertex array bound).
inline constexpr const char* kFullScreenTriangle = R"(#version 450 core
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

/// GLSL sources of one program; empty stages are left out.
struct ShaderSources {
  std::string vertex, geometry, fragment;
};

/// Owns a linked GL program. Compile or link failures throw GlError whose message names
/// `name`, the stage and GL's info log. Move-only; uniforms are set with
/// glProgramUniform* (no bind needed). Belongs to its context's thread.
class Program {
 public:
  Program(std::string_view name, const ShaderSources& sources);
  /// A compute program of one compute shader (errors as above).
  [[nodiscard]] static Program compute(std::string_view name, const std::string& source);
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;
  Program(Program&& o) noexcept;
  Program& operator=(Program&& o) noexcept;
  ~Program();

  [[nodiscard]] Id id() const noexcept { return id_; }
  void use() const noexcept;
  /// Uniform location, or -1 if the program has no active uniform of that name (the
  /// compiler may drop unused ones; setting -1 is a no-op in GL).
  [[nodiscard]] int uniform(const char* name) const noexcept;

  void set(const char* name, float v) const noexcept;
  void set(const char* name, int v) const noexcept;
  void set(const char* name, const glm::vec2& v) const noexcept;
  void set(const char* name, const glm::vec3& v) const noexcept;
  void set(const char* name, const glm::vec4& v) const noexcept;
  void set(const char* name, const glm::ivec2& v) const noexcept;
  void set(const char* name, const glm::mat4& m) const noexcept;
  void set(const char* name, const glm::mat3& m) const noexcept;

 private:
  Program() = default;
  void link(std::string_view name, const std::vector<Id>& shaders);

  Id id_ = 0;
};

}  // namespace regolith::gl
