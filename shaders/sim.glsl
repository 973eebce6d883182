// One pass of a mass-spring step for one node, shared by the transform-feedback (step.vert)
// and the compute (step.comp) pipelines. The physics is core/node_physics.h; this file binds it
// to GLSL and to the GL pipelines' buffers, and runs one pass of the integrator's schedule.
// The including shader defines, before this file:
//   vec4 src_x(int j), src_v(int j)  the state the forces are evaluated at (x.w: inverse mass)
// and, on grids, after it (it reads params):
//   ivec3 node_cell(int i)           node i's grid coordinates (node_physics.h's grid_node inverted)
// and the host defines PASS (one of the PASS_* below), STAGE (the pass's stage, 0..3),
// RULE (node_physics.h's RULE_*), TOPOLOGY_GRID (with STENCIL_SIZE, STENCIL_VOLUME and
// STENCIL_OFFSETS: the stencil's entries, whether it is a lattice's, and their offsets) or
// TOPOLOGY_GENERAL, and MATH_EXACT or MATH_FAST (the pipeline option "math": the CPU float
// pipeline's operations, see exact_math.glsl, or what the driver makes of the plain ones).
// With EXTERNAL_FORCES (the hybrid pipelines) another API's force pass wrote each node's
// acceleration, which the including shader reads as vec4 forces_acc(int i).

#define real float
#define DL_FN
#define CREF(T) T
#define OUT(T) DL_PRECISE out T
#define INOUT(T) DL_PRECISE inout T
#define VEC3(a, b, c) vec3(a, b, c)
#define DL_FINITE(a) ((floatBitsToUint(a) & 0x7f800000u) != 0x7f800000u)
#define DL_INFINITY uintBitsToFloat(0x7f800000u)
#if defined(MATH_EXACT)
#include "exact_math.glsl"
#define DL_PRECISE precise
#define DL_RECIP(a) dl_recip(a)
#define DL_RSQRT(a) dl_recip(dl_sqrt(a))
#define DL_DOT(a, b) dl_dot(a, b)
#define DL_LENGTH(a) dl_length(a)
#elif defined(MATH_FAST)
#define DL_PRECISE
#define DL_RECIP(a) (real(1) / (a))
#define DL_RSQRT(a) inversesqrt(a)
#define DL_DOT(a, b) dot(a, b)
#define DL_LENGTH(a) length(a)
#else
#error the host defines MATH_EXACT or MATH_FAST
#endif
#include "node_physics.h"

#define PASS_ONE 0     // one force pass and the step's result: o0 = x', o1 = (v', displacement)
#define PASS_STAGE 1   // forces at stage STAGE, then stage STAGE+1: o0 = a, o1 = x, o2 = v
#define PASS_RESULT 2  // forces at the last stage, then the step's result: o0 = x', o1 = (v', displacement)

// Static for a run; mirrored by SimBlock in gl/gl_pipeline.cpp.
layout(std140, binding = 0) uniform Sim {
  StepParams params;
  StencilEntry stencil[MAX_STENCIL];
};

uniform vec3 u_drag_force_target;  // spring drag: target at this pass's force time
uniform vec3 u_drag_next;          // hard drag: target at t + dt
uniform float u_weights[4];        // Runge-Kutta weights of the slopes 0..STAGE (PASS_ONE: b_0)
uniform bool u_half_step;          // Verlet: v is the half step's (State::half_step)

// Earlier stages' slopes: velocities of stage states 1..3, accelerations of stages 0..2.
layout(binding = 2) uniform samplerBuffer u_stage_v[3];
layout(binding = 5) uniform samplerBuffer u_stage_a[3];

#ifdef TOPOLOGY_GENERAL
// Node -> incident springs (CSR): offsets [n+1]; links [2s]: (other node's bits, rest, k, kd),
// in views of LINK_VIEW texels (within the driver's texture-buffer limit): view 0 at unit 9,
// views 1-3 at units 11-13.
layout(binding = 8) uniform isamplerBuffer u_adj_offset;
layout(binding = 9) uniform samplerBuffer u_links;
layout(binding = 11) uniform samplerBuffer u_links_more[3];

vec4 link(int e) {
  if (e < LINK_VIEW) return texelFetch(u_links, e);
  int view = e / LINK_VIEW, at = e - view * LINK_VIEW;
  if (view == 1) return texelFetch(u_links_more[0], at);
  if (view == 2) return texelFetch(u_links_more[1], at);
  return texelFetch(u_links_more[2], at);
}
#endif

#ifdef TOPOLOGY_GRID
ivec3 node_cell(int i);
// The stencil's offsets. Fast math: compile-time constants, the loops over them unrolled
// (NVIDIA's pragma; other drivers ignore it). Exact math keeps its long loop body rolled, the
// offsets read from the uniform block: unrolled, it ran 4-6% slower on the H100 (13% while its
// floor divisions were integer divisions), where fast math ran 4.7% faster (2048^2 cloth).
#ifdef MATH_FAST
#pragma optionNV(unroll all)
const ivec3 kStencilOffset[STENCIL_SIZE] = STENCIL_OFFSETS;
#define STENCIL_OFFSET(e) kStencilOffset[e]
#else
#define STENCIL_OFFSET(e) ivec3(stencil[e].di, stencil[e].dj, stencil[e].dk)
#endif
#endif

vec3 springs_on(int i, vec3 xi, vec3 vi) {
  DL_PRECISE vec3 f = vec3(0.0);
#ifdef TOPOLOGY_GRID
  // STENCIL_SIZE entries (a compile-time count, so that the loops can unroll); only nodes near a
  // border check whether each neighbour is in the grid.
  ivec3 c = node_cell(i);
  int layer = params.nx * params.ny;
  if (grid_interior(params, c.x, c.y, c.z, STENCIL_VOLUME)) {
    for (int e = 0; e < STENCIL_SIZE; ++e) {
      ivec3 o = STENCIL_OFFSET(e);
      int j = i + o.x + o.y * params.nx + o.z * layer;
      f += spring_force(xi, src_x(j).xyz, vi, src_v(j).xyz, stencil[e].k, stencil[e].kd, stencil[e].rest);
    }
    return f;
  }
  for (int e = 0; e < STENCIL_SIZE; ++e) {
    ivec3 o = STENCIL_OFFSET(e);
    int j = grid_neighbour(params, c.x, c.y, c.z, o.x, o.y, o.z);
    if (j >= 0) f += spring_force(xi, src_x(j).xyz, vi, src_v(j).xyz, stencil[e].k, stencil[e].kd, stencil[e].rest);
  }
#else
  int end = texelFetch(u_adj_offset, i + 1).x;
  for (int e = texelFetch(u_adj_offset, i).x; e < end; ++e) {
    vec4 l = link(e);
    int j = floatBitsToInt(l.x);
    f += spring_force(xi, src_x(j).xyz, vi, src_v(j).xyz, l.z, l.w, l.y);
  }
#endif
  return f;
}

// The pass for node i from the current state (x0, v0); o2 is written by stage passes only.
void node_pass(int i, vec4 x0, vec4 v0, out vec4 o0, out vec4 o1, out vec4 o2) {
  float w = x0.w, dt = params.dt;
  vec3 xs = src_x(i).xyz, vs = src_v(i).xyz;
#ifdef EXTERNAL_FORCES
  vec3 a = forces_acc(i).xyz;
#else
  vec3 a = node_fixed(params, i, w) ? vec3(0.0)
                                    : node_acceleration(params, i, w, xs, vs, springs_on(i, xs, vs), u_drag_force_target);
#endif
  vec3 x, v;
  o2 = vec4(0.0);
#if PASS == PASS_ONE
  one_pass_update(RULE, u_weights[0], x0.xyz, v0.xyz, a, u_half_step, dt, x, v);
#else
  vec3 dx = vec3(0.0), dv = vec3(0.0);
  if (STAGE > 0 && u_weights[0] != 0.0) add_slope(dx, dv, u_weights[0], v0.xyz, texelFetch(u_stage_a[0], i).xyz);
  for (int j = 1; j < STAGE; ++j)
    if (u_weights[j] != 0.0)
      add_slope(dx, dv, u_weights[j], texelFetch(u_stage_v[j - 1], i).xyz, texelFetch(u_stage_a[j], i).xyz);
  if (u_weights[STAGE] != 0.0) add_slope(dx, dv, u_weights[STAGE], vs, a);
  rk_state(x0.xyz, v0.xyz, dx, dv, dt, x, v);
#if PASS == PASS_STAGE
  o0 = vec4(a, 0.0);
  o1 = vec4(x, w);
  o2 = vec4(v, 0.0);
  return;
#endif
#endif
  constrain_node(params, i, w, x0.xyz, u_drag_next, x, v);
  o0 = vec4(x, w);
  o1 = vec4(v, displacement(x, x0.xyz, v));
}
