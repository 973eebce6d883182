#version 430 core
// Two-sided Lambert shading with a head light for surfaces (a mesh's triangles flat, their
// normal from the screen-space derivatives of the position); flat colour for points.
in vec3 v_normal;
in vec3 v_world;
uniform vec3 u_eye;
uniform bool u_surface;
uniform bool u_mesh;
out vec4 frag;

void main() {
  vec3 base = vec3(0.93, 0.55, 0.22);
  if (!u_surface && !u_mesh) {
    frag = vec4(base, 1.0);
    return;
  }
  vec3 n = u_mesh ? cross(dFdx(v_world), dFdy(v_world)) : v_normal;
  vec3 l = normalize(u_eye - v_world);
  float diffuse = length(n) > 0.0 ? abs(dot(normalize(n), l)) : 1.0;
  frag = vec4(base * (0.25 + 0.75 * diffuse), 1.0);
}
