#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/gl/Program.hpp>

#include <glm/gtc/type_ptr.hpp>

#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace regolith::gl {

namespace {

std::string shaderLog(GLuint shader) {
  GLint len = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &len);
  std::string log(static_cast<std::size_t>(len > 0 ? len : 1), '\0');
  glGetShaderInfoLog(shader, len, nullptr, log.data());
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  return log;
}

std::string programLog(GLuint program) {
  GLint len = 0;
  glGetProgramiv(program, GL_INFO_LOG_LENGTH, &len);
  std::string log(static_cast<std::size_t>(len > 0 ? len : 1), '\0');
  glGetProgramInfoLog(program, len, nullptr, log.data());
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  return log;
}

GLuint compile(std::string_view name, GLenum stage, const char* stageName,
               const std::string& source) {
  const GLuint s = glCreateShader(stage);
  const char* text = source.c_str();
  glShaderSource(s, 1, &text, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (ok == 0) {
    const std::string log = shaderLog(s);
    glDeleteShader(s);
    throw GlError("Program(): '" + std::string(name) + "': " + stageName +
                  " shader does not compile:\n" + log);
  }
  return s;
}

}  // namespace

Program::Program(std::string_view name, const ShaderSources& sources) {
  std::vector<GLuint> shaders;
  const auto cleanup = [&] {
    for (GLuint s : shaders) glDeleteShader(s);
  };
  try {
    if (!sources.vertex.empty())
      shaders.push_back(compile(name, GL_VERTEX_SHADER, "vertex", sources.vertex));
    if (!sources.geometry.empty())
      shaders.push_back(compile(name, GL_GEOMETRY_SHADER, "geometry", sources.geometry));
    if (!sources.fragment.empty())
      shaders.push_back(compile(name, GL_FRAGMENT_SHADER, "fragment", sources.fragment));
  } catch (...) {
    cleanup();
    throw;
  }
  try {
    link(name, shaders);
  } catch (...) {
    cleanup();
    throw;
  }
  cleanup();
}

static_assert(std::is_same_v<GLint, int>, "Program::uniform() returns GLint as int");

void Program::use() const noexcept { glUseProgram(id_); }

void Program::link(std::string_view name, const std::vector<Id>& shaders) {
  id_ = glCreateProgram();
  for (GLuint s : shaders) glAttachShader(id_, s);
  glLinkProgram(id_);
  for (GLuint s : shaders) glDetachShader(id_, s);
  GLint ok = 0;
  glGetProgramiv(id_, GL_LINK_STATUS, &ok);
  if (ok == 0) {
    const std::string log = programLog(id_);
    glDeleteProgram(id_);
    id_ = 0;
    throw GlError("Program(): '" + std::string(name) + "' does not link:\n" + log);
  }
}

Program Program::compute(std::string_view name, const std::string& source) {
  const GLuint shader = compile(name, GL_COMPUTE_SHADER, "compute", source);
  Program p;
  try {
    p.link(name, {shader});
  } catch (...) {
    glDeleteShader(shader);
    throw;
  }
  glDeleteShader(shader);
  return p;
}

Program::Program(Program&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
Program& Program::operator=(Program&& o) noexcept {
  if (this != &o) {
    if (id_ != 0) glDeleteProgram(id_);
    id_ = std::exchange(o.id_, 0);
  }
  return *this;
}
Program::~Program() {
  if (id_ != 0) glDeleteProgram(id_);
}

GLint Program::uniform(const char* name) const noexcept { return glGetUniformLocation(id_, name); }
void Program::set(const char* name, float v) const noexcept {
  glProgramUniform1f(id_, uniform(name), v);
}
void Program::set(const char* name, int v) const noexcept {
  glProgramUniform1i(id_, uniform(name), v);
}
void Program::set(const char* name, const glm::vec2& v) const noexcept {
  glProgramUniform2fv(id_, uniform(name), 1, glm::value_ptr(v));
}
void Program::set(const char* name, const glm::vec3& v) const noexcept {
  glProgramUniform3fv(id_, uniform(name), 1, glm::value_ptr(v));
}
void Program::set(const char* name, const glm::vec4& v) const noexcept {
  glProgramUniform4fv(id_, uniform(name), 1, glm::value_ptr(v));
}
void Program::set(const char* name, const glm::ivec2& v) const noexcept {
  glProgramUniform2iv(id_, uniform(name), 1, glm::value_ptr(v));
}
void Program::set(const char* name, const glm::mat4& m) const noexcept {
  glProgramUniformMatrix4fv(id_, uniform(name), 1, GL_FALSE, glm::value_ptr(m));
}
void Program::set(const char* name, const glm::mat3& m) const noexcept {
  glProgramUniformMatrix3fv(id_, uniform(name), 1, GL_FALSE, glm::value_ptr(m));
}

}  // namespace regolith::gl
