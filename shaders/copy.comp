#version 430 core
// Copies one vec4 per node between storage buffers. Uploads into node buffers go through it:
// on the H100, data that GL's buffer-transfer calls put into memory imported from CUDA was not
// seen by CUDA at larger sizes, while shader writes were.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Src { vec4 src[]; };
layout(std430, binding = 1) writeonly buffer Dst { vec4 dst[]; };
uniform int u_n;

void main() {
  for (uint i = gl_GlobalInvocationID.x; i < uint(u_n); i += gl_NumWorkGroups.x * 256u) dst[i] = src[i];
}
