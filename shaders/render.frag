#version 430 core
// Two-sided Lambert shading with a head light for surfaces (a mesh's triangles flat, their
// normal from the screen-space derivatives of the position); flat colour for points. Colour
// by speed or strain: the value over u_scale from blue (0) through green to red (u_scale and
// above); a mesh triangle's strain is the largest relative change of its three edges.
layout(binding = 0) uniform samplerBuffer u_pos;
layout(binding = 1) uniform samplerBuffer u_rest;
layout(binding = 3) uniform isamplerBuffer u_tri;  // a mesh's triangles, 3 node indices each
in vec3 v_normal;
in vec3 v_world;
in float v_value;
uniform vec3 u_eye;
uniform bool u_surface;
uniform bool u_mesh;
uniform int u_colour;  // 0 plain, 1 speed, 2 strain
uniform float u_scale;
out vec4 frag;

float edge_strain(int a, int b) {
  return abs(length(texelFetch(u_pos, a).xyz - texelFetch(u_pos, b).xyz) /
             length(texelFetch(u_rest, a).xyz - texelFetch(u_rest, b).xyz) - 1.0);
}

vec3 ramp(float s) {
  s = clamp(s, 0.0, 1.0);
  return vec3(smoothstep(0.4, 0.9, s), 1.0 - abs(2.0 * s - 1.0), 1.0 - smoothstep(0.1, 0.6, s));
}

void main() {
  vec3 base = vec3(0.93, 0.55, 0.22);
  float value = v_value;
  if (u_colour == 2 && u_mesh) {
    int t = 3 * gl_PrimitiveID;
    int a = texelFetch(u_tri, t).x, b = texelFetch(u_tri, t + 1).x, c = texelFetch(u_tri, t + 2).x;
    value = max(edge_strain(a, b), max(edge_strain(b, c), edge_strain(c, a)));
  }
  if (u_colour != 0) base = ramp(value / u_scale);
  if (!u_surface && !u_mesh) {
    frag = vec4(base, 1.0);
    return;
  }
  vec3 n = u_mesh ? cross(dFdx(v_world), dFdy(v_world)) : v_normal;
  vec3 l = normalize(u_eye - v_world);
  float diffuse = length(n) > 0.0 ? abs(dot(normalize(n), l)) : 1.0;
  frag = vec4(base * (0.25 + 0.75 * diffuse), 1.0);
}
