#version 430 core
// glsl-compute's bare gather: step.comp's loads and stores on an n x n cloth (its work groups,
// its stencil, the fast build's unrolled loops) without its arithmetic. Each invocation reads its
// node's x and v and its neighbours' x and v (step.comp reads them for every spring), and
// writes them back with the neighbours' components summed in, so that no load is dead.
// Defines: TILE_X, TILE_Y, STENCIL_SIZE, STENCIL_OFFSETS.
layout(local_size_x = TILE_X, local_size_y = TILE_Y) in;
layout(std430, binding = 0) readonly buffer X { vec4 x[]; };
layout(std430, binding = 1) readonly buffer V { vec4 v[]; };
layout(std430, binding = 2) writeonly buffer XO { vec4 xo[]; };
layout(std430, binding = 3) writeonly buffer VO { vec4 vo[]; };
layout(location = 0) uniform int u_n;

#pragma optionNV(unroll all)
const ivec3 kOffset[STENCIL_SIZE] = STENCIL_OFFSETS;

void main() {
  ivec2 c = ivec2(gl_GlobalInvocationID.xy);
  if (c.x >= u_n || c.y >= u_n) return;
  int node = c.y * u_n + c.x;
  vec4 sx = x[node], sv = v[node];
  bool inside = c.x >= 2 && c.x < u_n - 2 && c.y >= 2 && c.y < u_n - 2;
  for (int e = 0; e < STENCIL_SIZE; ++e) {
    ivec2 o = c + kOffset[e].xy;
    if (!inside && (o.x < 0 || o.x >= u_n || o.y < 0 || o.y >= u_n)) continue;
    int j = o.y * u_n + o.x;
    sx.xyz += x[j].xyz;
    sv.xyz += v[j].xyz;
  }
  xo[node] = sx;
  vo[node] = sv;
}
