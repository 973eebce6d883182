#version 430 core
// Draws the state straight from the position buffer (a texture buffer over one band of the
// nodes, by gl_VertexID): points, a mesh's triangles (gl_VertexID is then the index from
// the element buffer), or a cloth surface made here with no index buffer: 6 vertices per
// quad of the grid sampled every u_stride nodes, normals from the neighbours. Colour by speed
// or strain (render.frag) reads the rest and previous positions over the same band.
layout(binding = 0) uniform samplerBuffer u_pos;
layout(binding = 1) uniform samplerBuffer u_rest;  // colour by strain
layout(binding = 2) uniform samplerBuffer u_prev;  // colour by speed: the positions last drawn
uniform mat4 u_view_proj;
uniform ivec2 u_grid;     // cloth nx, ny (surface mode)
uniform bool u_surface;
uniform float u_point_size;
uniform int u_stride;     // surface: nodes between drawn rows and columns
uniform int u_first;      // points: first node of this band; surface: first quad row
uniform int u_tex_first;  // node at texel 0 of u_pos
uniform int u_colour;     // 0 plain, 1 speed, 2 strain
uniform float u_frame_dt; // simulated time since the positions in u_prev, s (0: none)
out vec3 v_normal;
out vec3 v_world;
out float v_value;        // speed (m/s) or a cloth node's strain

// Texel of node (i, j) of the cloth, clamped to the grid.
int texel(int i, int j) {
  return clamp(j, 0, u_grid.y - 1) * u_grid.x + clamp(i, 0, u_grid.x - 1) - u_tex_first;
}
vec3 p(int i, int j) { return texelFetch(u_pos, texel(i, j)).xyz; }
vec3 r(int i, int j) { return texelFetch(u_rest, texel(i, j)).xyz; }

// The larger relative change of the node's spans to its neighbours along i and along j.
float grid_strain(int i, int j, int s) {
  float su = length(p(i + s, j) - p(i - s, j)) / length(r(i + s, j) - r(i - s, j)) - 1.0;
  float sv = length(p(i, j + s) - p(i, j - s)) / length(r(i, j + s) - r(i, j - s)) - 1.0;
  return max(abs(su), abs(sv));
}

void main() {
  vec3 x;
  int t;
  v_normal = vec3(0.0);
  v_value = 0.0;
  if (u_surface) {
    // quad (qi, qj) of the sampled grid; corners a c b, b c d with a = (i, j), d = (i+1, j+1)
    int cols = (u_grid.x - 2) / u_stride + 1;  // quads along i
    int q = gl_VertexID / 6, corner = gl_VertexID % 6;
    int qi = q % cols, qj = u_first + q / cols;
    int di = (corner == 2 || corner == 3 || corner == 5) ? 1 : 0;
    int dj = (corner == 1 || corner == 4 || corner == 5) ? 1 : 0;
    int i = min((qi + di) * u_stride, u_grid.x - 1), j = min((qj + dj) * u_stride, u_grid.y - 1);
    t = texel(i, j);
    x = p(i, j);
    vec3 du = p(i + u_stride, j) - p(i - u_stride, j);
    vec3 dv = p(i, j + u_stride) - p(i, j - u_stride);
    vec3 n = cross(dv, du);
    float len = length(n);
    v_normal = len > 0.0 ? n / len : vec3(0.0, 1.0, 0.0);
    if (u_colour == 2) v_value = grid_strain(i, j, u_stride);
  } else {
    t = u_first + gl_VertexID - u_tex_first;
    x = texelFetch(u_pos, t).xyz;
  }
  if (u_colour == 1 && u_frame_dt > 0.0) v_value = length(x - texelFetch(u_prev, t).xyz) / u_frame_dt;
  v_world = x;
  gl_Position = u_view_proj * vec4(x, 1.0);
  gl_PointSize = u_point_size;
}
