// glsl_compat.h — just enough GLSL for C++ to compile the shared tracer code (shaders/tracer/*.glsl):
// vector types with GLSL constructors and operators, and the built-in functions that code uses.
// C++ only; GLSL has all of this built in.
#ifndef BVHLAB_GLSL_COMPAT_H
#define BVHLAB_GLSL_COMPAT_H
#ifndef __cplusplus
#error "glsl_compat.h is for C++"
#endif
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace bvhlab::gpu {

using uint = std::uint32_t;

struct vec2 {
    float x = 0, y = 0;
    constexpr vec2() = default;
    constexpr explicit vec2(float s) : x(s), y(s) {}
    constexpr vec2(float x_, float y_) : x(x_), y(y_) {}
};

struct vec3 {
    float x = 0, y = 0, z = 0;
    constexpr vec3() = default;
    constexpr explicit vec3(float s) : x(s), y(s), z(s) {}
    constexpr vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
    float operator[](uint i) const {  // an indexed load, not a chain of branches on a random axis
        const float v[3] = {x, y, z};
        return v[i];
    }
};

struct vec4 {
    float x = 0, y = 0, z = 0, w = 0;
    constexpr vec4() = default;
    constexpr explicit vec4(float s) : x(s), y(s), z(s), w(s) {}
    constexpr vec4(float x_, float y_, float z_, float w_) : x(x_), y(y_), z(z_), w(w_) {}
    constexpr vec4(vec3 v, float w_) : x(v.x), y(v.y), z(v.z), w(w_) {}
};

struct uvec2 {
    uint x = 0, y = 0;
    constexpr uvec2() = default;
    constexpr uvec2(uint x_, uint y_) : x(x_), y(y_) {}
};

struct uvec4 {
    uint x = 0, y = 0, z = 0, w = 0;
    constexpr uvec4() = default;
    constexpr uvec4(uint x_, uint y_, uint z_, uint w_) : x(x_), y(y_), z(z_), w(w_) {}
};

#define BVHLAB_VEC_OPS(V, APPLY)                              \
    inline V operator+(V a, V b) { return APPLY(a, b, +); }   \
    inline V operator-(V a, V b) { return APPLY(a, b, -); }   \
    inline V operator*(V a, V b) { return APPLY(a, b, *); }   \
    inline V operator/(V a, V b) { return APPLY(a, b, /); }   \
    inline V operator*(V a, float s) { return a * V(s); }     \
    inline V operator*(float s, V a) { return V(s) * a; }     \
    inline V operator/(V a, float s) { return a / V(s); }     \
    inline V operator+(V a, float s) { return a + V(s); }     \
    inline V operator-(V a, float s) { return a - V(s); }     \
    inline V& operator+=(V& a, V b) { return a = a + b; }     \
    inline V& operator-=(V& a, V b) { return a = a - b; }     \
    inline V& operator*=(V& a, V b) { return a = a * b; }     \
    inline V& operator*=(V& a, float s) { return a = a * s; } \
    inline V operator-(V a) { return V(0.0f) - a; }
#define BVHLAB_APPLY2(a, b, op) vec2(a.x op b.x, a.y op b.y)
#define BVHLAB_APPLY3(a, b, op) vec3(a.x op b.x, a.y op b.y, a.z op b.z)
#define BVHLAB_APPLY4(a, b, op) vec4(a.x op b.x, a.y op b.y, a.z op b.z, a.w op b.w)
BVHLAB_VEC_OPS(vec2, BVHLAB_APPLY2)
BVHLAB_VEC_OPS(vec3, BVHLAB_APPLY3)
BVHLAB_VEC_OPS(vec4, BVHLAB_APPLY4)
#undef BVHLAB_VEC_OPS
#undef BVHLAB_APPLY2
#undef BVHLAB_APPLY3
#undef BVHLAB_APPLY4

// GLSL's min/max/clamp: for NaN arguments GLSL leaves the result undefined; these return y.
inline float min(float a, float b) { return b < a ? b : a; }
inline float max(float a, float b) { return a < b ? b : a; }
inline uint min(uint a, uint b) { return b < a ? b : a; }
inline uint max(uint a, uint b) { return a < b ? b : a; }
inline float clamp(float x, float lo, float hi) { return min(max(x, lo), hi); }
inline vec3 min(vec3 a, vec3 b) { return {min(a.x, b.x), min(a.y, b.y), min(a.z, b.z)}; }
inline vec3 max(vec3 a, vec3 b) { return {max(a.x, b.x), max(a.y, b.y), max(a.z, b.z)}; }
inline vec3 clamp(vec3 x, float lo, float hi) { return {clamp(x.x, lo, hi), clamp(x.y, lo, hi), clamp(x.z, lo, hi)}; }
inline float abs(float x) { return std::fabs(x); }
inline vec3 abs(vec3 v) { return {std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}; }
inline float sqrt(float x) { return std::sqrt(x); }
inline float pow(float x, float y) { return std::pow(x, y); }
inline float floor(float x) { return std::floor(x); }
inline float fract(float x) { return x - std::floor(x); }
inline float tan(float x) { return std::tan(x); }
inline float sin(float x) { return std::sin(x); }
inline float cos(float x) { return std::cos(x); }
inline float mix(float a, float b, float t) { return a * (1.0f - t) + b * t; }
inline vec3 mix(vec3 a, vec3 b, float t) { return a * (1.0f - t) + b * t; }
inline float dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline vec3 cross(vec3 a, vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(vec3 v) { return std::sqrt(dot(v, v)); }
inline vec3 normalize(vec3 v) { return v * (1.0f / length(v)); }
inline vec3 reflect(vec3 i, vec3 n) { return i - n * (2.0f * dot(n, i)); }
inline vec3 refract(vec3 i, vec3 n, float eta) {  // the GLSL definition
    float d = dot(n, i);
    float k = 1.0f - eta * eta * (1.0f - d * d);
    return k < 0.0f ? vec3(0.0f) : i * eta - n * (eta * d + std::sqrt(k));
}
inline uint floatBitsToUint(float f) { return std::bit_cast<uint>(f); }
inline float uintBitsToFloat(uint u) { return std::bit_cast<float>(u); }

}  // namespace bvhlab::gpu

// Parameter qualifiers of the shared code, and its constants (the shared code is compiled as
// members of a class, see core_cpp/src/render/cpu_tracer.h); INLINE marks the functions of shared
// code that C++ compiles at namespace scope in a header (geometry.glsl, shared_geometry.h).
#define INOUT(T) T&
#define OUT(T) T&
#define LOCAL_CONST static constexpr
#define INLINE inline
#define PRECISE  // GLSL's `precise` (no contraction into fma): C++ contracts nothing (-ffp-contract=off)

#endif  // BVHLAB_GLSL_COMPAT_H
