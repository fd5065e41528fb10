// Metro-style surface comparison (Cignoni, Rocchini, Scopigno: "Metro: measuring error on
// simplified surfaces", Computer Graphics Forum 1998): the distance between two triangle meshes
// estimated by sampling each surface uniformly by area and measuring every sample's distance to
// the other surface exactly (TriangleBvh). The one-sided distance a->b is the distribution of
// d(p, b) for p on a; its max is the one-sided Hausdorff distance; the two-sided max is the
// Hausdorff distance. At each sample the attributes both meshes have are compared as well (the
// appearance error a LOD makes), interpolated barycentrically at the sample (on the sampled
// mesh) and at its closest point (on the other mesh).
#pragma once

#include <array>
#include <cstdint>

#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod::measure {

struct MetroOptions {
  // Samples per direction (a->b and b->a each take this many). 0: automatic, 10 per triangle
  // of the sampled mesh, at least 100'000 and at most 1'000'000 — about 1 s for a 1M-triangle
  // pair on 2 cores. More samples tighten the mean/RMS estimates (error ~ 1/sqrt(samples)) and
  // catch narrower spikes for the max, which sampling can only underestimate.
  std::uint64_t samples = 0;
  // Seed of the counter-based sample generator: the same seed gives bit-identical reports for
  // any thread count.
  std::uint64_t seed = 1;
  // Query threads; 0: std::thread::hardware_concurrency().
  unsigned threads = 0;
};

// Deviation statistics of one direction (samples on one mesh, measured against the other) or of
// both pooled together.
struct Deviation {
  std::uint64_t samples = 0;
  // Distance to the other surface, model units.
  double mean = 0.0;
  double rms = 0.0;
  double max = 0.0;
  // The same divided by MetroReport::diagonal (the bounding-box diagonal of mesh a).
  double mean_relative = 0.0;
  double rms_relative = 0.0;
  double max_relative = 0.0;
  // Where `max` is reached, model units: the sample (on the sampled mesh; the first of equal
  // ones in sample order) and its closest point on the other mesh. Zero without samples.
  std::array<double, 3> max_at{};
  std::array<double, 3> max_closest{};

  // Attributes compared at the samples: those both meshes have. A field is 0 when its attribute
  // is not compared.
  VertexLayout compared;
  // Angle between the interpolated (renormalized) unit normals, degrees. Samples where either
  // interpolated normal has zero length are left out of both numbers.
  double normal_mean_degrees = 0.0;
  double normal_max_degrees = 0.0;
  // RMS of the Euclidean RGB distance, colour units 0..1 (max possible sqrt(3)).
  double color_rms = 0.0;
  // RMS of the Euclidean (u, v) distance, texture units. Across a UV seam the closest point can
  // land on the other side of the seam; such samples show as outliers.
  double uv_rms = 0.0;
};

struct MetroReport {
  double diagonal = 0.0;  // bounding-box diagonal of mesh a, model units
  double area_a = 0.0;    // surface areas, model units squared
  double area_b = 0.0;
  Deviation a_to_b;       // samples on a, distances to b
  Deviation b_to_a;       // samples on b, distances to a
  // Both sample sets pooled: mean and RMS over all samples, max = the Hausdorff distance,
  // attribute numbers over all samples.
  Deviation two_sided;
  unsigned threads = 1;   // query threads used
  double seconds = 0.0;   // wall time of evaluate()
};

// Compares two meshes. Positions only decide the distances; normals/colours/uvs are compared
// where both layouts have them. Errors (bad_input): a mesh with no triangles or zero total area,
// indices out of range or not a multiple of 3, vertices not a multiple of the layout, non-finite
// positions or coordinates beyond ±1e18 (their squared distances would overflow float). Memory: about 64 bytes per triangle of each mesh (two TriangleBvh) plus O(samples /
// 4096) for the deterministic partial sums; the samples themselves are never stored.
Result<MetroReport> evaluate(const NodeMesh& a, const NodeMesh& b, const MetroOptions& options = {});

}  // namespace octolod::measure
