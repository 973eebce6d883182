#version 430 core
// The scene's obstacles, made here with no vertex buffer, 6 vertices a quad: the ground as one
// square (u_kind 0: centre u_center, half its side u_size), a sphere as u_grid.x slices by
// u_grid.y stacks of quads between its poles (u_kind 1: centre u_center, radius u_size; its
// faces wind counter-clockwise seen from outside). Both are drawn u_inset behind their surface
// (the ground that much lower, a sphere's vertices that much further along their rays from the
// eye, where they keep their pixels: its outline keeps its size), so that a model resting on
// them, exactly on their surface where the constraints put it, is seen in front of them, not
// interleaved. v_world is the surface itself, for lighting and the ground's clipping.
uniform mat4 u_view_proj;
uniform vec3 u_eye;
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
    v_world = u_center + vec3(uv.x, 0.0, uv.y) * u_size;
  } else {
    float phi = 2.0 * PI * float(q % u_grid.x + corner.x) / float(u_grid.x);
    float theta = PI * float(q / u_grid.x + corner.y) / float(u_grid.y);
    v_normal = vec3(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
    v_world = u_center + u_size * v_normal;
  }
  vec3 drawn = u_kind == 0 ? v_world - vec3(0.0, u_inset, 0.0) : v_world + u_inset * normalize(v_world - u_eye);
  gl_Position = u_view_proj * vec4(drawn, 1.0);
}
