#version 430 core
// The obstacles lit as render.frag lights surfaces (Lambert, a head light): the ground as a
// checkerboard of grey squares u_check wide, spheres blue-grey. Where there is a ground (at
// height u_ground), a sphere's points on its other side from the eye are hidden by it.
in vec3 v_world;
in vec3 v_normal;
uniform vec3 u_eye;
uniform int u_kind;
uniform float u_check;
uniform bool u_has_ground;
uniform float u_ground;
out vec4 frag;

void main() {
  if (u_kind == 1 && u_has_ground && (v_world.y - u_ground) * (u_eye.y - u_ground) < 0.0) discard;
  vec3 base = vec3(0.35, 0.5, 0.7);
  if (u_kind == 0) {
    ivec2 cell = ivec2(floor(v_world.xz / u_check));
    base = ((cell.x + cell.y) & 1) == 0 ? vec3(0.42) : vec3(0.34);
  }
  float diffuse = abs(dot(normalize(v_normal), normalize(u_eye - v_world)));
  frag = vec4(base * (0.35 + 0.65 * diffuse), 1.0);
}
