// OSMesa context creation and shader linking (see gl_context.h).
#include "renderer/map/gl_context.h"

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include "core/error.h"

namespace nurbsrt {
namespace {

[[noreturn]] void fail(const std::string& who, const std::string& what) {
    throw Error(ErrorCode::internal, who + ": " + what);
}

GLuint compile(GLenum type, const char* src, const std::string& who) {
    const GLuint sh = glCreateShader(type);
    glShaderSource(sh, 1, &src, nullptr);
    glCompileShader(sh);
    GLint ok = 0;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = {};
        glGetShaderInfoLog(sh, sizeof log, nullptr, log);
        fail(who, std::string("shader compilation failed: ") + log);
    }
    return sh;
}

}  // namespace

GlContext::GlContext() {
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           0,
                           OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION,
                           4,
                           OSMESA_CONTEXT_MINOR_VERSION,
                           5,
                           0};
    ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!ctx_) fail("OSMesa", "OSMesaCreateContextAttribs (OpenGL 4.5 core) failed");
}

GlContext::~GlContext() {
    if (ctx_) OSMesaDestroyContext(static_cast<OSMesaContext>(ctx_));
}

void GlContext::make_current() {
    if (!OSMesaMakeCurrent(static_cast<OSMesaContext>(ctx_), dummy_, GL_UNSIGNED_BYTE, 4, 4))
        fail("OSMesa", "OSMesaMakeCurrent failed");
}

void GlContext::release_current() { OSMesaMakeCurrent(nullptr, nullptr, GL_UNSIGNED_BYTE, 0, 0); }

unsigned int GlContext::link_program(const char* vertex_src, const char* fragment_src, const std::string& who) {
    make_current();
    const GLuint vs = compile(GL_VERTEX_SHADER, vertex_src, who);
    const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment_src, who);
    const GLuint program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) fail(who, "shader link failed");
    return program;
}

}  // namespace nurbsrt
