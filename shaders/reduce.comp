#version 430 core
// The largest displacement of the last step: the max of its stop-rule terms, the w of the
// velocities (non-negative floats, whose bits order like the floats; +inf flags a non-finite
// node), reduced per work group, then one atomicMax into the step's word.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Velocities { vec4 v[]; };
layout(std430, binding = 1) buffer Result { uint max_bits[2]; };  // a word per state set
uniform int u_n;
uniform int u_word;
shared uint part[256];

void main() {
  uint l = gl_LocalInvocationID.x;
  uint m = 0u;
  for (uint j = gl_GlobalInvocationID.x; j < uint(u_n); j += gl_NumWorkGroups.x * 256u)
    m = max(m, floatBitsToUint(v[j].w));
  part[l] = m;
  barrier();
  for (uint s = 128u; s > 0u; s >>= 1) {
    if (l < s) part[l] = max(part[l], part[l + s]);
    barrier();
  }
  if (l == 0u) atomicMax(max_bits[u_word], part[0]);
}
