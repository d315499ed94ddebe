// glsl_prelude.glsl — the GLSL side of glsl_compat.h: what the shared tracer code needs that
// GLSL spells differently from C++.
#define INOUT(T) inout T
#define OUT(T) out T
#define LOCAL_CONST const
#define INLINE
#define PRECISE precise
vec3 xyz(vec4 v) { return v.xyz; }
