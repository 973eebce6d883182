#version 430 core
// Two-sided Lambert shading with a head light for surfaces; flat colour for points.
in vec3 v_normal;
in vec3 v_world;
uniform vec3 u_eye;
uniform bool u_surface;
out vec4 frag;

void main() {
  vec3 base = vec3(0.93, 0.55, 0.22);
  if (!u_surface) {
    frag = vec4(base, 1.0);
    return;
  }
  vec3 l = normalize(u_eye - v_world);
  float diffuse = abs(dot(normalize(v_normal), l));
  frag = vec4(base * (0.25 + 0.75 * diffuse), 1.0);
}
