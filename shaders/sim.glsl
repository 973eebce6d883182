// One mass-spring step for one node, shared by the transform-feedback (step.vert) and the
// compute (step.comp) pipelines: the arithmetic of core/forces.hpp and core/cpu_backend.cpp.
// The including shader defines, before this file:
//   vec4 src_x(int j), src_v(int j)  the state the forces are evaluated at (x.w: inverse mass)
//   vec4 acc_x(int i), acc_v(int i)  the running sums of a multi-pass combine
// and the host defines PASS (one of the PASS_* below) and TOPOLOGY_GRID or TOPOLOGY_GENERAL.
// With EXTERNAL_FORCES (the hybrid pipelines) another API's force pass wrote each node's
// acceleration, which the including shader reads as vec4 forces_acc(int i).

#define PASS_EXPLICIT_EULER 0
#define PASS_SEMI_IMPLICIT_EULER 1
#define PASS_VERLET 2
#define PASS_STAGE 3    // forces at a stage state, the next stage state and the running sums
#define PASS_COMBINE 4  // forces at the last stage, the combined step and the constraints

#define DRAG_NONE 0
#define DRAG_HARD 1
#define DRAG_SPRING 2

// Static for a run; layout mirrored by SimParams in gl/gl_pipeline.cpp.
layout(std140, binding = 0) uniform SimParams {
  ivec4 dims;          // nx, ny, nz, node count
  vec4 gravity_dt;     // gravity (m/s^2), dt (s)
  vec4 wind_damping;   // wind force (N), global damping c (N s/m)
  vec4 stiffness;      // per spring kind (N/m); w: drag spring stiffness
  vec4 spring_damping; // per spring kind (N s/m)
  vec4 dt_terms;       // dt^2, dt^2/2, 1/dt, ground height
  ivec4 flags;         // drag node, drag mode, has ground, sphere count
  ivec4 stencil_size;  // x: offsets in the half stencil (grids)
  vec4 spheres[8];     // centre, radius
  ivec4 stencil[16];   // grid offset (di, dj, dk), spring kind
  vec4 stencil_rest[16];  // x: rest length of the offset's springs (m)
};

uniform vec3 u_drag_force_target;  // spring drag: target at this pass's force time
uniform vec3 u_drag_next;          // hard drag: target at t + dt
uniform float u_stage_h;           // stage: coef * dt
uniform float u_weight;            // combine weight of this pass's slope (0: not summed)
uniform bool u_first;              // first pass of a multi-pass step: the sums start at zero
uniform bool u_has_prev;           // Verlet: previous positions are valid

#ifdef TOPOLOGY_GENERAL
// Node -> incident springs (CSR): offsets [n+1]; entries (other node, spring kind) [2s]; rest lengths [2s].
layout(binding = 4) uniform isamplerBuffer u_adj_offset;
layout(binding = 5) uniform isamplerBuffer u_adj;
layout(binding = 6) uniform samplerBuffer u_adj_rest;
#endif

// f_i = -(k (|d| - l) + kd (v_i - v_j).u) u,  d = x_i - x_j; coincident nodes exert none.
vec3 spring_force(vec3 xi, vec3 xj, vec3 vi, vec3 vj, float k, float kd, float rest) {
  vec3 d = xi - xj;
  float len = length(d);
  if (len == 0.0) return vec3(0.0);
  vec3 u = d * (1.0 / len);
  float s = k * (len - rest) + kd * dot(vi - vj, u);
  return u * (-s);
}

vec3 acceleration(int i, vec3 xi, vec3 vi, float w) {
  if (w == 0.0 || (flags.y == DRAG_HARD && i == flags.x)) return vec3(0.0);
  vec3 f = vec3(0.0);
#ifdef TOPOLOGY_GRID
  // Neighbours by arithmetic: every offset of the half stencil, both ways.
  ivec3 c = ivec3(i % dims.x, (i / dims.x) % dims.y, i / (dims.x * dims.y));
  for (int s = 0; s < stencil_size.x; ++s) {
    ivec4 o = stencil[s];
    float k = stiffness[o.w], kd = spring_damping[o.w], rest = stencil_rest[s].x;
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      ivec3 q = c + sgn * o.xyz;
      if (all(greaterThanEqual(q, ivec3(0))) && all(lessThan(q, dims.xyz))) {
        int j = (q.z * dims.y + q.y) * dims.x + q.x;
        f += spring_force(xi, src_x(j).xyz, vi, src_v(j).xyz, k, kd, rest);
      }
    }
  }
#else
  int end = texelFetch(u_adj_offset, i + 1).x;
  for (int e = texelFetch(u_adj_offset, i).x; e < end; ++e) {
    ivec2 jk = texelFetch(u_adj, e).xy;
    f += spring_force(xi, src_x(jk.x).xyz, vi, src_v(jk.x).xyz, stiffness[jk.y], spring_damping[jk.y],
                      texelFetch(u_adj_rest, e).x);
  }
#endif
  if (flags.y == DRAG_SPRING && i == flags.x) f += (u_drag_force_target - xi) * stiffness.w;
  return (f + wind_damping.xyz - vi * wind_damping.w) * w + gravity_dt.xyz;
}

// Pins, the hard drag, the ground plane and the spheres, after the update.
void constrain(int i, vec3 x_old, float w, inout vec3 x, inout vec3 v) {
  if (w == 0.0) {
    x = x_old;
    v = vec3(0.0);
  } else if (flags.y == DRAG_HARD && i == flags.x) {
    x = u_drag_next;
    v = (x - x_old) * dt_terms.z;
  } else {
    if (flags.z != 0 && x.y < dt_terms.w) {
      x.y = dt_terms.w;
      if (v.y < 0.0) v.y = 0.0;
    }
    for (int s = 0; s < flags.w; ++s) {
      vec3 d = x - spheres[s].xyz;
      float len = length(d);
      if (len >= spheres[s].w) continue;
      vec3 n = len > 0.0 ? d * (1.0 / len) : vec3(0.0, 1.0, 0.0);
      x = spheres[s].xyz + n * spheres[s].w;
      float vn = dot(v, n);
      if (vn < 0.0) v -= n * vn;
    }
  }
}

// |x - x_old|, or +inf when anything is not finite (tested on the bits, immune to fast math),
// so that a max over nodes of the bit patterns flags divergence.
float displacement(vec3 x, vec3 x_old, vec3 v) {
  float d = length(x - x_old);
  const uint e = 0x7f800000u;
  uvec4 bits = floatBitsToUint(vec4(v, d)) & uvec4(e);
  uvec3 xb = floatBitsToUint(x) & uvec3(e);
  return (any(equal(bits, uvec4(e))) || any(equal(xb, uvec3(e)))) ? uintBitsToFloat(e) : d;
}

// The pass for node i from the current state (x0, v0) and, for Verlet, the previous
// position xp. Outputs: o0 = position (w: inverse mass), o1 = velocity (w: displacement of
// the step) on fused and combine passes; stage passes write the stage state to o0, o1 and
// the running sums to o2, o3; Verlet writes the new previous position to o2.
void node_pass(int i, vec4 x0, vec4 v0, vec4 xp, out vec4 o0, out vec4 o1, out vec4 o2, out vec4 o3) {
  float w = x0.w, dt = gravity_dt.w;
  vec3 xs = src_x(i).xyz, vs = src_v(i).xyz;
#ifdef EXTERNAL_FORCES
  vec3 a = forces_acc(i).xyz;
#else
  vec3 a = acceleration(i, xs, vs, w);
#endif
  vec3 x, v;
  o2 = vec4(0.0);
  o3 = vec4(0.0);
#if PASS == PASS_EXPLICIT_EULER
  x = x0.xyz + v0.xyz * dt;
  v = v0.xyz + a * dt;
#elif PASS == PASS_SEMI_IMPLICIT_EULER
  v = v0.xyz + a * dt;
  x = x0.xyz + v * dt;
#elif PASS == PASS_VERLET
  vec3 s = u_has_prev ? (x0.xyz - xp.xyz) + a * dt_terms.x : v0.xyz * dt + a * dt_terms.y;
  x = x0.xyz + s;
  v = s * dt_terms.z;
  o2 = x0;
#else
  vec3 sx = vec3(0.0), sv = vec3(0.0);
  if (!u_first) {
    sx = acc_x(i).xyz;
    sv = acc_v(i).xyz;
  }
  if (u_weight != 0.0) {
    sx += vs * u_weight;
    sv += a * u_weight;
  }
#if PASS == PASS_STAGE
  o0 = vec4(x0.xyz + vs * u_stage_h, w);
  o1 = vec4(v0.xyz + a * u_stage_h, 0.0);
  o2 = vec4(sx, 0.0);
  o3 = vec4(sv, 0.0);
  return;
#else
  x = x0.xyz + sx * dt;
  v = v0.xyz + sv * dt;
#endif
#endif
  constrain(i, x0.xyz, w, x, v);
  o0 = vec4(x, w);
  o1 = vec4(v, displacement(x, x0.xyz, v));
}
