#version 430 core
// The scene's obstacles, made here with no vertex buffer, 6 vertices a quad: the ground as one
// square (u_kind 0: centre u_center, half its side u_size), a sphere as u_grid.x slices by
// u_grid.y stacks of quads between its poles (u_kind 1: centre u_center, radius u_size; its
// faces wind counter-clockwise seen from outside). Both are drawn u_inset inside their
// surface (the ground lower, a sphere smaller, but by half its radius at most), so that a model
// resting on them, exactly on their surface where the constraints put it, is seen in front of
// them, not interleaved.
uniform mat4 u_view_proj;
uniform int u_kind;
uniform vec3 u_center;
uniform float u_size;
uniform ivec2 u_grid;
uniform float u_inset;
out vec3 v_world;
out vec3 v_normal;

const float PI = 3.14159265;

void main() {
  int q = gl_VertexID / 6, c = gl_VertexID % 6;
  // The quad's corners (0, 0) (1, 0) (1, 1), (0, 0) (1, 1) (0, 1).
  ivec2 corner = ivec2(c == 1 || c == 2 || c == 4 ? 1 : 0, c == 2 || c == 4 || c == 5 ? 1 : 0);
  if (u_kind == 0) {
    vec2 uv = vec2(corner) * 2.0 - 1.0;
    v_normal = vec3(0.0, 1.0, 0.0);
    v_world = u_center + vec3(uv.x, -u_inset, uv.y) * vec3(u_size, 1.0, u_size);
  } else {
    float phi = 2.0 * PI * float(q % u_grid.x + corner.x) / float(u_grid.x);
    float theta = PI * float(q / u_grid.x + corner.y) / float(u_grid.y);
    v_normal = vec3(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
    v_world = u_center + max(u_size - u_inset, 0.5 * u_size) * v_normal;
  }
  gl_Position = u_view_proj * vec4(v_world, 1.0);
}
