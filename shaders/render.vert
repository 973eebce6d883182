#version 430 core
// Draws the state straight from the position buffer (a texture buffer over one band of the
// nodes, by gl_VertexID): points, a mesh's triangles (gl_VertexID is then the index from
// the element buffer), or a cloth surface made here with no index buffer: 6 vertices per
// quad of the grid sampled every u_stride nodes, normals from the neighbours.
layout(binding = 0) uniform samplerBuffer u_pos;
uniform mat4 u_view_proj;
uniform ivec2 u_grid;     // cloth nx, ny (surface mode)
uniform bool u_surface;
uniform float u_point_size;
uniform int u_stride;     // surface: nodes between drawn rows and columns
uniform int u_first;      // points: first node of this band; surface: first quad row
uniform int u_tex_first;  // node at texel 0 of u_pos
out vec3 v_normal;
out vec3 v_world;

// Node (i, j) of the cloth, clamped to the grid.
vec3 p(int i, int j) {
  i = clamp(i, 0, u_grid.x - 1);
  j = clamp(j, 0, u_grid.y - 1);
  return texelFetch(u_pos, j * u_grid.x + i - u_tex_first).xyz;
}

void main() {
  vec3 x;
  v_normal = vec3(0.0);
  if (u_surface) {
    // quad (qi, qj) of the sampled grid; corners a c b, b c d with a = (i, j), d = (i+1, j+1)
    int cols = (u_grid.x - 2) / u_stride + 1;  // quads along i
    int q = gl_VertexID / 6, corner = gl_VertexID % 6;
    int qi = q % cols, qj = u_first + q / cols;
    int di = (corner == 2 || corner == 3 || corner == 5) ? 1 : 0;
    int dj = (corner == 1 || corner == 4 || corner == 5) ? 1 : 0;
    int i = min((qi + di) * u_stride, u_grid.x - 1), j = min((qj + dj) * u_stride, u_grid.y - 1);
    x = p(i, j);
    vec3 du = p(i + u_stride, j) - p(i - u_stride, j);
    vec3 dv = p(i, j + u_stride) - p(i, j - u_stride);
    vec3 n = cross(dv, du);
    float len = length(n);
    v_normal = len > 0.0 ? n / len : vec3(0.0, 1.0, 0.0);
  } else {
    x = texelFetch(u_pos, u_first + gl_VertexID - u_tex_first).xyz;
  }
  v_world = x;
  gl_Position = u_view_proj * vec4(x, 1.0);
  gl_PointSize = u_point_size;
}
