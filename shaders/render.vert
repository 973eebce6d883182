#version 430 core
// Draws the state straight from the position buffer (a texture buffer, by gl_VertexID):
// points, or a cloth surface whose normals come from the grid neighbours here.
layout(binding = 0) uniform samplerBuffer u_pos;
uniform mat4 u_view_proj;
uniform ivec2 u_grid;   // cloth nx, ny (surface mode)
uniform bool u_surface;
uniform float u_point_size;
out vec3 v_normal;
out vec3 v_world;

vec3 p(int i, int j) { return texelFetch(u_pos, j * u_grid.x + i).xyz; }

void main() {
  int id = gl_VertexID;
  vec3 x = texelFetch(u_pos, id).xyz;
  v_normal = vec3(0.0);
  if (u_surface) {
    int i = id % u_grid.x, j = id / u_grid.x;
    vec3 du = p(min(i + 1, u_grid.x - 1), j) - p(max(i - 1, 0), j);
    vec3 dv = p(i, min(j + 1, u_grid.y - 1)) - p(i, max(j - 1, 0));
    vec3 n = cross(dv, du);
    float len = length(n);
    v_normal = len > 0.0 ? n / len : vec3(0.0, 1.0, 0.0);
  }
  v_world = x;
  gl_Position = u_view_proj * vec4(x, 1.0);
  gl_PointSize = u_point_size;
}
