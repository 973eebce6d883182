// The per-node stages of a mass-spring step, written once for every backend: the CPU
// pipelines and the CUDA kernels include it through core/physics.hpp (as static members of
// Physics<Real>), the GLSL shaders through shaders/sim.glsl. It is therefore written in the
// subset the three languages share. The includer defines:
//   real, vec3               the scalar and 3-vector types (float / vec3 in GLSL)
//   DL_FN                    a function's qualifiers (host + device in CUDA, static members in C++)
//   CREF(T) OUT(T) INOUT(T)  parameter passing: const T& / T& in C++; T / out T / inout T in GLSL
//   VEC3(x, y, z)            a vector from its components
//   DL_FINITE(a)             whether a scalar is finite (immune to fast math in GLSL)
//   DL_INFINITY              +infinity
//   DL_RECIP(a), DL_RSQRT(a), DL_DOT(a, b), DL_LENGTH(a)
//                            1 / a, 1 / sqrt(a), a.b, |a|: the plain operations in C++ and CUDA
//                            (nvcc's fast math makes 1 / sqrt one instruction); in GLSL's exact
//                            math correctly rounded, and in C++'s order
//   DL_PRECISE               GLSL's precise in exact math, else nothing: on the locals a
//                            function's result is computed in (OUT and INOUT carry it), as precise
//                            covers what a function computes into its own precise variables
// No include guard: C++ includes it once per precision.

#define DRAG_NONE 0
#define DRAG_HARD 1    // the node is kinematic and sits on its target after every step
#define DRAG_SPRING 2  // a spring of drag_stiffness pulls the node towards its target

// Update rules (Schedule::rule): how a step's result is formed from its force passes.
#define RULE_RUNGE_KUTTA 0         // s0 + dt sum_j b_j k_j, slopes k_j = (v_j, a_j)
#define RULE_SEMI_IMPLICIT_EULER 1 // v' = v + dt a, x' = x + dt v'
#define RULE_VERLET 2              // leapfrog: as above, v at half steps (the first kick dt/2)

#define ZERO3 VEC3(real(0), real(0), real(0))
#define MAX_SPHERES 8
#define MAX_STENCIL 32  // lattice: 6 structural + 20 shear + 6 flexion neighbours

struct Sphere {
  vec3 center;  // m
  real radius;  // m
};

// What every node's step reads, constant for a run. For float this is also the std140 layout
// of the GLSL uniform block (each vec3 is followed by a scalar, each row is 16 bytes).
struct StepParams {
  vec3 gravity;  // m/s^2
  real dt;       // s
  vec3 wind;     // N on every free node
  real damping;  // global velocity damping c, N s/m
  int drag_node;        // -1: none
  int drag_mode;        // DRAG_*
  real drag_stiffness;  // N/m (DRAG_SPRING)
  int has_ground;       // 0 or 1
  real ground;          // plane y = ground
  int sphere_count;
  int nx, ny;           // grid dimensions (node (i, j, k) = (k ny + j) nx + i)
  int nz, node_count;
  int pad0, pad1;       // std140: the spheres start on 16 bytes
  Sphere spheres[MAX_SPHERES];
};

// One neighbour of a grid node: the offset to it and its spring's constants.
struct StencilEntry {
  int di, dj, dk;
  real rest;  // m
  real k;     // stiffness, N/m
  real kd;    // damping along the spring, N s/m
  int pad0, pad1;
};

DL_FN int grid_node(int i, int j, int k, int nx, int ny) { return (k * ny + j) * nx + i; }
// Node n's coordinate along one axis, grid_node inverted: i = grid_axis(n, 1, nx),
// j = grid_axis(n, nx, ny), k = grid_axis(n, nx * ny, nz).
DL_FN int grid_axis(int n, int stride, int size) { return (n / stride) % size; }

// How far a grid node's springs reach along an axis (flexion springs: two nodes; the test of
// core/grid_stencil.hpp's table checks it).
#define STENCIL_REACH 2

// Whether every stencil neighbour of node (i, j, k) lies in the grid (layers: the stencil also
// reaches along k, as a lattice's does), so that a gather need not check each one.
DL_FN bool grid_interior(CREF(StepParams) p, int i, int j, int k, bool layers) {
  return i >= STENCIL_REACH && i < p.nx - STENCIL_REACH && j >= STENCIL_REACH && j < p.ny - STENCIL_REACH &&
         (!layers || (k >= STENCIL_REACH && k < p.nz - STENCIL_REACH));
}

// Node (i, j, k) + (di, dj, dk), or -1 when that lies outside the grid.
DL_FN int grid_neighbour(CREF(StepParams) p, int i, int j, int k, int di, int dj, int dk) {
  int a = i + di, b = j + dj, c = k + dk;
  if (a < 0 || a >= p.nx || b < 0 || b >= p.ny || c < 0 || c >= p.nz) return -1;
  return grid_node(a, b, c, p.nx, p.ny);
}

// Force on node i from a spring to node j (Hooke + damping along the spring axis):
//   f_i = -(k (|d| - l) + kd (v_i - v_j).u) u,  d = x_i - x_j,  u = d / |d|,
// evaluated as  -(k (1 - l r) + kd ((v_i - v_j).d r) r) d  with r = 1 / |d|: one reciprocal square
// root a spring (one instruction in fast math) and no division. (The paper's eq. (2) drops the
// minus sign.) |d|^2 is taken as at least MIN_SQUARED_LENGTH, so that coincident nodes exert no
// force and nodes closer than 1e-15 m a bounded one. Written without branches, so that GPUs
// evaluate it as one straight run of instructions (and with fast math contract the result into
// the caller's sum).
#define MIN_SQUARED_LENGTH real(1e-30)  // m^2
DL_FN vec3 spring_force(vec3 xi, vec3 xj, vec3 vi, vec3 vj, real k, real kd, real rest) {
  vec3 d = xi - xj;
  real q = DL_DOT(d, d);
  real r = DL_RSQRT(q > MIN_SQUARED_LENGTH ? q : MIN_SQUARED_LENGTH);
  real c = k * (real(1) - rest * r) + kd * (DL_DOT(vi - vj, d) * r * r);
  DL_PRECISE vec3 f = d * (-c);
  return f;
}

// Pinned nodes (zero inverse mass) and the hard-dragged node have no acceleration.
DL_FN bool node_fixed(CREF(StepParams) p, int i, real inv_mass) {
  return inv_mass == real(0) || (p.drag_mode == DRAG_HARD && i == p.drag_node);
}

// Acceleration of node i from the sum of its spring forces: the drag spring's pull, wind,
// global damping and gravity: a = (f + wind - c v) / m + g.
DL_FN vec3 node_acceleration(CREF(StepParams) p, int i, real inv_mass, vec3 x, vec3 v, vec3 springs,
                             vec3 drag_target) {
  if (node_fixed(p, i, inv_mass)) return ZERO3;
  vec3 f = springs;
  if (p.drag_mode == DRAG_SPRING && i == p.drag_node) f += (drag_target - x) * p.drag_stiffness;
  DL_PRECISE vec3 a = (f + p.wind - v * p.damping) * inv_mass + p.gravity;
  return a;
}

// Runge-Kutta: a stage state, or a step's result, is s0 + dt sum_j w_j k_j. add_slope adds
// one term w_j k_j to the sums (dx, dv); rk_state forms the state from them.
DL_FN void add_slope(INOUT(vec3) dx, INOUT(vec3) dv, real w, vec3 vj, vec3 aj) {
  dx += vj * w;
  dv += aj * w;
}
DL_FN void rk_state(vec3 x0, vec3 v0, vec3 dx, vec3 dv, real dt, OUT(vec3) x, OUT(vec3) v) {
  x = x0 + dx * dt;
  v = v0 + dv * dt;
}

// The result of a schedule with one force pass: rule RULE_*, weight b_0 of a one-stage
// Runge-Kutta scheme (explicit Euler). Verlet in its leapfrog form: v is the velocity of the
// half step before (x' - x = dt v'), kicked by a whole step, and at the start (half_step false,
// v the velocity at t) by half a step: x' = x + dt v + dt^2/2 a. Position Verlet's
// x' = 2x - x_prev + dt^2 a is the same scheme, but takes a contact's projection of x for a
// velocity; the leapfrog keeps the velocity the contact left.
DL_FN void one_pass_update(int rule, real weight, vec3 x, vec3 v, vec3 a, bool half_step, real dt, OUT(vec3) xo,
                           OUT(vec3) vo) {
  if (rule == RULE_SEMI_IMPLICIT_EULER || rule == RULE_VERLET) {
    vo = v + a * (rule == RULE_VERLET && !half_step ? real(0.5) * dt : dt);
    xo = x + vo * dt;
  } else {
    vec3 dx = ZERO3, dv = ZERO3;
    add_slope(dx, dv, weight, v, a);
    rk_state(x, v, dx, dv, dt, xo, vo);
  }
}

// Ground plane y >= h: clamp the position, remove the velocity into the ground.
DL_FN void ground_constraint(INOUT(vec3) x, INOUT(vec3) v, real h) {
  if (x.y < h) {
    x.y = h;
    if (v.y < real(0)) v.y = real(0);
  }
}

// Sphere collider: a node inside is projected onto the surface (paper eq. 13, corrected)
// and its inward normal velocity removed. A node at the exact centre goes out along +y.
DL_FN void sphere_constraint(INOUT(vec3) x, INOUT(vec3) v, vec3 c, real r) {
  vec3 d = x - c;
  real len = DL_LENGTH(d);
  if (len >= r) return;
  vec3 n = len > real(0) ? d * DL_RECIP(len) : VEC3(real(0), real(1), real(0));
  x = c + n * r;
  real vn = DL_DOT(v, n);
  if (vn < real(0)) v -= n * vn;
}

// The constraints after a step's update: pinned nodes stay where they were, the hard-dragged
// node sits on its target (drag_target: at the end of the step), other nodes are pushed out of
// the ground and the spheres.
DL_FN void constrain_node(CREF(StepParams) p, int i, real inv_mass, vec3 x_old, vec3 drag_target,
                          INOUT(vec3) x, INOUT(vec3) v) {
  if (inv_mass == real(0)) {
    x = x_old;
    v = ZERO3;
  } else if (p.drag_mode == DRAG_HARD && i == p.drag_node) {
    x = drag_target;
    v = (x - x_old) * DL_RECIP(p.dt);
  } else {
    if (p.has_ground != 0) ground_constraint(x, v, p.ground);
    for (int q = 0; q < p.sphere_count; ++q) sphere_constraint(x, v, p.spheres[q].center, p.spheres[q].radius);
  }
}

// A node's term of the stop rule's reduction: |x - x_old|, or infinity when the new state is
// not finite, so that the largest term over nodes also flags divergence.
DL_FN real displacement(vec3 x, vec3 x_old, vec3 v) {
  real d = DL_LENGTH(x - x_old);
  bool ok = DL_FINITE(d) && DL_FINITE(v.x) && DL_FINITE(v.y) && DL_FINITE(v.z);
  return ok ? d : DL_INFINITY;
}

// Energies (physics checks): a free node's kinetic energy and its potential in the constant
// force fields (gravity, wind); a spring's potential energy.
DL_FN real kinetic_energy(real inv_mass, vec3 v) {
  if (inv_mass == real(0)) return real(0);
  return real(0.5) * DL_RECIP(inv_mass) * DL_DOT(v, v);
}
DL_FN real field_energy(CREF(StepParams) p, real inv_mass, vec3 x) {
  if (inv_mass == real(0)) return real(0);
  return -DL_DOT(p.gravity * DL_RECIP(inv_mass) + p.wind, x);
}
DL_FN real spring_energy(vec3 xi, vec3 xj, real k, real rest) {
  real stretch = DL_LENGTH(xi - xj) - rest;
  return real(0.5) * k * stretch * stretch;
}
