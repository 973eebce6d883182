#version 430 core
// The same step as step.vert, as a compute shader over shader storage buffers. A dispatch
// covers one window of nodes (gl/gl_pipeline.hpp, node_windows): the inputs are bound from
// node u_read_first, the outputs from node u_first.
// On grids a work group is a tile of TILE_X x TILE_Y nodes (rows of nx nodes, a lattice's
// layers stacked), so that the rows its springs reach come through the cache once for the
// tile; the dispatch covers the window's rows from u_first_row, tile rows along y then z.
// General models: 256 nodes a work group, along x then y.
#ifdef TOPOLOGY_GRID
layout(local_size_x = TILE_X, local_size_y = TILE_Y) in;
#else
layout(local_size_x = 256) in;
#endif
layout(location = 0) uniform int u_first;       // first node this dispatch writes
layout(location = 1) uniform int u_count;       // nodes it writes
layout(location = 2) uniform int u_read_first;  // first node of the bound inputs
layout(location = 3) uniform int u_first_row;   // grids: the row of node u_first
layout(location = 4) uniform int u_word;        // result passes: this step's stop-rule word
layout(location = 5) uniform uint u_launch;     // result passes: their number (low 32 bits)

layout(std430, binding = 0) readonly buffer S0X { vec4 s0_x[]; };  // current state
layout(std430, binding = 1) readonly buffer S0V { vec4 s0_v[]; };
layout(std430, binding = 2) readonly buffer SrcX { vec4 src_x_[]; };  // forces evaluated here
layout(std430, binding = 3) readonly buffer SrcV { vec4 src_v_[]; };
layout(std430, binding = 4) writeonly buffer O0 { vec4 out0[]; };
layout(std430, binding = 5) writeonly buffer O1 { vec4 out1[]; };
layout(std430, binding = 6) writeonly buffer O2 { vec4 out2[]; };

vec4 src_x(int j) { return src_x_[j - u_read_first]; }
vec4 src_v(int j) { return src_v_[j - u_read_first]; }
#ifdef EXTERNAL_FORCES
layout(std430, binding = 7) readonly buffer ForcesAcc { vec4 forces_acc_[]; };  // from the force stage
vec4 forces_acc(int i) { return forces_acc_[i - u_read_first]; }
#endif

#include "sim.glsl"

#ifdef TOPOLOGY_GRID
ivec3 cell_;  // the invocation's node, set by main
ivec3 node_cell(int i) { return cell_; }
#endif

#if PASS != PASS_STAGE
// The stop rule's reduction in the pass that writes the step's result: each work group takes
// the largest term of its nodes (o1.w, non-negative, +inf where not finite) as float bits,
// which order as the floats do, into the step's word, which the step before cleared. Work
// group 0 of the first window posts the other word, the step before's (complete: its pass
// ended at a barrier), to the host, tagged with that pass's number, and clears it for the step
// after.
layout(std430, binding = 8) buffer StepMax { uint step_max[2]; };
layout(std430, binding = 9) writeonly buffer Posted { uvec2 posted; };  // mapped by the host
shared uint group_term;
#endif

void main() {
#ifdef TOPOLOGY_GRID
  uint tile_row = gl_WorkGroupID.z * gl_NumWorkGroups.y + gl_WorkGroupID.y;
  int row = u_first_row + int(tile_row * uint(TILE_Y) + gl_LocalInvocationID.y), col = int(gl_GlobalInvocationID.x);
  int l = col < params.nx ? row * params.nx + col - u_first : -1;  // -1: outside the window
  int k = STENCIL_VOLUME ? row / params.ny : 0;  // rows of layers stacked: row = k ny + j
  cell_ = ivec3(col, row - k * params.ny, k);
#else
  // Work groups run x by y when there are more than the driver's x limit (dispatch_shape).
  int l = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 256u);
#endif
#if PASS != PASS_STAGE
  if (gl_LocalInvocationIndex == 0u) group_term = 0u;
  barrier();  // every invocation reaches the barriers: none returns early
#endif
  if (l >= 0 && l < u_count) {
    int i = u_first + l, r = i - u_read_first;
    vec4 o0, o1, o2;
    node_pass(i, s0_x[r], s0_v[r], o0, o1, o2);
    out0[l] = o0;
    out1[l] = o1;
#if PASS == PASS_STAGE
    out2[l] = o2;
#endif
#if PASS != PASS_STAGE
    atomicMax(group_term, floatBitsToUint(o1.w));
#endif
  }
#if PASS != PASS_STAGE
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    atomicMax(step_max[u_word], group_term);
    if (gl_WorkGroupID == uvec3(0u) && u_first == 0) {
      posted = uvec2(u_launch - 1u, step_max[1 - u_word]);
      step_max[1 - u_word] = 0u;
    }
  }
#endif
}
