// libFuzzer target: meshes as a loader hands them over (any coordinates, NaN and infinity
// among them, any element indices, repeated, degenerate and non-manifold elements) through the
// repair, the model builder and every node order. Bad meshes must end in std::invalid_argument;
// any other exception, a crash, a sanitizer report or a model that breaks its invariants (a
// spring index out of range, a rest length not finite and positive, an order that is not a
// permutation) is a finding.
//
// Input: a flags byte (bit 0 volume, bit 1 lumped masses, bits 2-3 the node order), a vertex
// count, 3 bytes per vertex (a coordinate on a coarse grid, so welds and degenerate elements
// are common; 0x80 stands for NaN), then elements of 3 or 4 signed index bytes to the end.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "core/mesh_model.hpp"
#include "core/node_order.hpp"

namespace {

void require(bool ok) {
  if (!ok) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace deformlab;
  if (size < 2) return 0;
  const std::uint8_t flags = data[0];
  const std::size_t vertices = data[1];
  std::size_t at = 2;
  Mesh m;
  auto coordinate = [](std::uint8_t b) {
    return b == 0x80 ? std::numeric_limits<float>::quiet_NaN() : float(std::int8_t(b)) * 0.25f;
  };
  for (std::size_t v = 0; v < vertices && at + 3 <= size; ++v, at += 3)
    m.position.push_back({coordinate(data[at]), coordinate(data[at + 1]), coordinate(data[at + 2])});
  const bool volume = flags & 1;
  const std::size_t corners = volume ? 4 : 3;
  for (; at + corners <= size; at += corners) {
    if (volume)
      m.tetrahedron.push_back({std::int8_t(data[at]), std::int8_t(data[at + 1]), std::int8_t(data[at + 2]),
                               std::int8_t(data[at + 3])});
    else
      m.triangle.push_back({std::int8_t(data[at]), std::int8_t(data[at + 1]), std::int8_t(data[at + 2])});
  }
  try {
    repair(m);
    Model model = mesh_model(m, Material{}, (flags & 2) ? 1.5f : 0.f);
    const int n = model.node_count();
    require(n == int(m.position.size()));
    for (std::size_t s = 0; s < model.spring_i.size(); ++s) {
      require(model.spring_i[s] >= 0 && model.spring_i[s] < model.spring_j[s] && model.spring_j[s] < n);
      require(std::isfinite(model.rest_length[s]) && model.rest_length[s] > 0.f);
    }
    for (float w : model.inv_mass) require(std::isfinite(w) && w > 0.f);
    const auto order = node_order(model, NodeOrder((flags >> 2) & 3), 7);
    std::vector<bool> seen(std::size_t(n), false);
    for (std::int32_t v : order) {
      require(v >= 0 && v < n && !seen[std::size_t(v)]);
      seen[std::size_t(v)] = true;
    }
    reorder(model, order);
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
