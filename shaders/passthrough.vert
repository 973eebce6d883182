#version 430 core
// Transform feedback that only copies two vec4 attributes: the ceiling of the TF route.
layout(location = 0) in vec4 in_x;
layout(location = 1) in vec4 in_v;
out vec4 o0, o1;
void main() {
  o0 = in_x;
  o1 = in_v;
}
