#version 430 core
// The paper's update: one vertex per node, the new state captured by transform feedback
// (the rasteriser discarded); neighbours read through texture buffers over the state.
layout(location = 0) in vec4 in_x;  // current position, w: inverse mass
layout(location = 1) in vec4 in_v;  // current velocity

layout(binding = 0) uniform samplerBuffer u_src_x;  // state the forces are evaluated at
layout(binding = 1) uniform samplerBuffer u_src_v;

vec4 src_x(int j) { return texelFetch(u_src_x, j); }
vec4 src_v(int j) { return texelFetch(u_src_v, j); }
#ifdef EXTERNAL_FORCES
layout(binding = 10) uniform samplerBuffer u_forces_acc;  // accelerations from the force stage
vec4 forces_acc(int i) { return texelFetch(u_forces_acc, i); }
#endif

#include "sim.glsl"

#ifdef TOPOLOGY_GRID
ivec3 node_cell(int i) {
  return ivec3(grid_axis(i, 1, params.nx), grid_axis(i, params.nx, params.ny),
               grid_axis(i, params.nx * params.ny, params.nz));
}
#endif

out vec4 o0, o1, o2;

void main() { node_pass(gl_VertexID, in_x, in_v, o0, o1, o2); }
