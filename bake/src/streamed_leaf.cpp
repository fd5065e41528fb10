// Oversize octree leaves built from their record file in passes of bounded memory (Lindstrom
// 2000 vertex clustering with the node boundary locked; seed 3.5, 4.4), see streamed_leaf.h.
#include "streamed_leaf.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <system_error>
#include <unordered_map>
#include <utility>

#include "cluster.h"
#include "error_bound.h"
#include "flat_hash.h"
#include "inside_out.h"
#include "node_index.h"
#include "octolod/bake/external_sort.h"
#include "octolod/bake/soup.h"
#include "octolod/formats/node_file.h"
#include "quadric.h"
#include "repeated_records.h"
#include "tree_paths.h"
#include "wedges.h"

namespace octolod::bake {
namespace {

namespace fs = std::filesystem;

using Position = std::array<std::uint32_t, 3>;  // the bits of x, y, z

Position position_bits(const float* p) {
  Position bits;
  std::memcpy(bits.data(), p, sizeof bits);
  return bits;
}

// Calls fn(chunk) for consecutive chunks of `chunk_triangles` records of the file (the last one
// shorter): the same chunks on every pass.
Status for_each_chunk(const fs::path& path, std::size_t record_bytes, std::uint64_t chunk_triangles,
                      const std::function<Status(std::span<const std::byte>)>& fn) {
  auto reader = RecordReader::open(path, record_bytes, record_bytes);
  if (!reader.ok()) return reader.status();
  std::vector<std::byte> chunk(static_cast<std::size_t>(
      std::min<std::uint64_t>(chunk_triangles, std::max<std::uint64_t>(reader->record_count(), 1)) *
      record_bytes));
  for (;;) {
    auto read = reader->read_into(chunk);
    if (!read.ok()) return read.status();
    if (read.value() == 0) return {};
    OCTOLOD_RETURN_IF_ERROR(fn(std::span<const std::byte>(chunk).first(read.value() * record_bytes)));
  }
}

// One edge between two distinct positions, the smaller (lexicographic bits) first.
struct EdgeRecord {
  std::array<std::uint32_t, 6> words;
};
constexpr std::size_t kEdgeBytes = sizeof(EdgeRecord);

std::uint64_t edge_hash(const std::byte* record) {
  std::uint32_t words[6];
  std::memcpy(words, record, sizeof words);
  return hash_words(words, 6);
}

// What the first pass learns: the counts and bounds of LOD 0, the surface area.
struct Survey {
  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;  // of LOD 0 (per chunk)
  Bounds bounds;
  double area = 0.0;
};

double triangle_area(const std::array<double, 3>& normal) {  // from triangle_normal
  return 0.5 * std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
}

// The corners of one soup record.
struct Corners {
  std::array<std::array<float, kMaxQuadricDim>, 3> vertex;
};
Corners load_corners(const std::byte* record, VertexLayout layout) {
  Corners c{};
  for (int k = 0; k < 3; ++k)
    std::memcpy(c.vertex[static_cast<std::size_t>(k)].data(), record + soup_corner_offset(layout, k), layout.bytes());
  return c;
}

// The wedges of the streamed clustering. The in-memory grid's wedges are the corners of a
// cluster connected through edges inside it (wedges.h), which needs every vertex of the node at
// once. Streaming, a cluster's corners are grouped by their attributes instead: a corner joins
// the cluster's first wedge whose first corner is on its side of every attribute seam (normals
// within 60 degrees, colour and uv channels within 0.25 of each other), else it starts a new one
// (at most kMaxWedges per cluster; past that, the nearest). The two sides of a seam (the rock's
// u jumping from 1 to 0, a box's faces meeting at 90 degrees) are then never averaged; a smooth
// field that changes by more than the tolerance within one cell is split into several wedges,
// which costs output vertices, not accuracy. Each wedge's attributes are the area-weighted mean
// of its corners'. Memory: per wedge, a few of the layout's floats (about the output vertices).
class AttributeWedges {
 public:
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;
  static constexpr std::uint32_t kMaxWedges = 8;

  explicit AttributeWedges(VertexLayout layout) : layout_(layout), m_(layout.floats() - 3) {}

  // The wedge of a corner of cluster `cluster` whose attributes (the floats after its
  // position) are `attributes`.
  std::uint32_t wedge_of(std::uint32_t cluster, const float* attributes) {
    if (cluster >= first_.size()) first_.resize(std::size_t{cluster} + 1, kNone);
    std::uint32_t nearest = kNone, count = 0;
    double nearest_distance = std::numeric_limits<double>::infinity();
    for (std::uint32_t w = first_[cluster]; w != kNone; w = next_[w], ++count) {
      const double d = distance(&first_attributes_[w * m_], attributes);
      if (d <= 1.0) return w;
      if (d < nearest_distance) nearest = w, nearest_distance = d;
    }
    if (count >= kMaxWedges) return nearest;
    const auto w = static_cast<std::uint32_t>(next_.size());
    next_.push_back(first_[cluster]);
    first_[cluster] = w;
    cluster_.push_back(cluster);
    first_attributes_.insert(first_attributes_.end(), attributes, attributes + m_);
    sum_.resize(sum_.size() + m_, 0.0);
    area_.push_back(0.0);
    return w;
  }
  void add(std::uint32_t wedge, double area, const float* attributes) {
    for (std::size_t i = 0; i < m_; ++i) sum_[wedge * m_ + i] += area * attributes[i];
    area_[wedge] += area;
  }
  // The wedge's attributes: the area-weighted mean, its first corner's when it has no area.
  void attributes(std::uint32_t wedge, double* out) const {
    for (std::size_t i = 0; i < m_; ++i)
      out[i] = area_[wedge] > 0.0 ? sum_[wedge * m_ + i] / area_[wedge] : first_attributes_[wedge * m_ + i];
  }
  std::size_t size() const { return area_.size(); }
  std::uint32_t cluster(std::uint32_t wedge) const { return cluster_[wedge]; }

 private:
  // max over the attribute groups of how far b is from a, in units of the group's tolerance:
  // at most 1 on the same side of every seam
  double distance(const float* a, const float* b) const {
    double worst = 0.0;
    std::size_t i = 0;
    if (layout_.normal) {
      const double cosine = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
      worst = (1.0 - cosine) / (1.0 - 0.5);  // cos 60 degrees
      i = 3;
    }
    for (; i < m_; ++i) worst = std::max(worst, std::fabs(double(a[i]) - b[i]) / 0.25);
    return worst;
  }

  VertexLayout layout_;
  std::size_t m_;                         // attribute floats per vertex
  std::vector<std::uint32_t> first_;      // per cluster: its latest wedge
  std::vector<std::uint32_t> next_;       // per wedge: the cluster's previous one
  std::vector<std::uint32_t> cluster_;    // per wedge
  std::vector<float> first_attributes_;   // per wedge: its first corner's attributes
  std::vector<double> sum_;               // per wedge: area-weighted attribute sums
  std::vector<double> area_;
};

class StreamedLeafBuilder {
 public:
  StreamedLeafBuilder(const fs::path& records, const StreamedLeafOptions& options)
      : records_(records),
        options_(options),
        layout_(options.layout),
        record_bytes_(soup_record_bytes(options.layout)) {}

  // The records' counts and bounds (LOD 0's), their area, and with `edges` the edge file of the
  // boundary search.
  Status survey(const fs::path* edges) {
    std::optional<RecordWriter> edge_writer;
    if (edges) {
      auto writer = RecordWriter::create(*edges, kEdgeBytes, std::size_t{1} << 20);
      if (!writer.ok()) return writer.status();
      edge_writer.emplace(std::move(writer).value());
    }
    auto visit = [&](std::span<const std::byte> chunk) -> Status {
      const std::uint64_t first = survey_.triangles;
      indexer_.index(chunk, layout_, mesh_);
      survey_.triangles += mesh_.triangle_count();
      survey_.vertices += mesh_.vertex_count();
      survey_.bounds.extend(mesh_.bounds());
      for (std::size_t r = 0; r < chunk.size() / record_bytes_; ++r) {
        const Corners c = load_corners(chunk.data() + r * record_bytes_, layout_);
        for (int k = 0; k < 3; ++k)
          for (int i = 0; i < 3; ++i)
            if (!std::isfinite(c.vertex[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)]))
              return bad_input_error(records_.string() + ": record " + std::to_string(first + r) +
                                     ": non-finite position");
        survey_.area += triangle_area(triangle_normal(c.vertex[0].data(), c.vertex[1].data(), c.vertex[2].data()));
        if (!edge_writer) continue;
        for (std::size_t k = 0; k < 3; ++k) {
          Position a = position_bits(c.vertex[k].data()), b = position_bits(c.vertex[(k + 1) % 3].data());
          if (a == b) continue;  // a degenerate triangle's collapsed edge is never a boundary edge
          if (b < a) std::swap(a, b);
          EdgeRecord e;
          std::copy(a.begin(), a.end(), e.words.begin());
          std::copy(b.begin(), b.end(), e.words.begin() + 3);
          OCTOLOD_RETURN_IF_ERROR(edge_writer->append(reinterpret_cast<const std::byte*>(&e), 1));
        }
      }
      return {};
    };
    OCTOLOD_RETURN_IF_ERROR(for_each_chunk(records_, record_bytes_, options_.chunk_triangles, visit));
    mesh_ = {};
    if (edge_writer) OCTOLOD_RETURN_IF_ERROR(edge_writer->finish());
    return {};
  }

  // The boundary: the edges used an odd number of times, found as runs of equal edge records
  // after a sort by their hash (records of different edges with equal hashes are told apart
  // within their run). Both ends of each are locked.
  Status find_boundary_positions(const fs::path& edges, const fs::path& sorted) {
    SortOptions sort;
    sort.memory_budget_bytes = options_.sort_budget_bytes;
    sort.work_dir = options_.work_dir;
    sort.threads = 1;
    auto sorted_stats = sort_records(edges, sorted, kEdgeBytes,
                                     [](std::span<const std::byte> records, std::span<std::uint64_t> keys) {
                                       for (std::size_t i = 0; i < keys.size(); ++i)
                                         keys[i] = edge_hash(records.data() + i * kEdgeBytes);
                                     },
                                     sort);
    if (!sorted_stats.ok()) return sorted_stats.status();
    std::error_code ignored;
    fs::remove(edges, ignored);
    auto reader = RecordReader::open(sorted, kEdgeBytes, std::size_t{1} << 20);
    if (!reader.ok()) return reader.status();
    std::vector<Position> locked;
    std::vector<std::pair<EdgeRecord, std::uint32_t>> run;  // distinct edges of one hash, uses
    std::uint64_t run_hash = 0;
    auto close_run = [&] {
      for (const auto& [edge, uses] : run) {
        if (uses % 2 == 0) continue;
        locked.push_back({edge.words[0], edge.words[1], edge.words[2]});
        locked.push_back({edge.words[3], edge.words[4], edge.words[5]});
      }
      run.clear();
    };
    for (;;) {
      auto block = reader->read();
      if (!block.ok()) return block.status();
      if (block->empty()) break;
      for (std::size_t i = 0; i < block->size(); i += kEdgeBytes) {
        const std::uint64_t hash = edge_hash(block->data() + i);
        if (!run.empty() && hash != run_hash) close_run();
        run_hash = hash;
        EdgeRecord edge;
        std::memcpy(&edge, block->data() + i, kEdgeBytes);
        auto same = std::find_if(run.begin(), run.end(), [&](const auto& r) { return r.first.words == edge.words; });
        if (same == run.end()) run.push_back({edge, 1});
        else ++same->second;
      }
    }
    close_run();
    fs::remove(sorted, ignored);
    std::sort(locked.begin(), locked.end());
    locked.erase(std::unique(locked.begin(), locked.end()), locked.end());
    locked_ = std::make_unique<FlatHashMap<3>>(locked.size());
    for (std::size_t i = 0; i < locked.size(); ++i) {
      bool inserted = false;
      locked_->find_or_insert(locked[i], static_cast<std::uint32_t>(i), inserted);
    }
    locked_count_ = locked.size();
    return {};
  }

  // The grid resolution for at most `limit` triangles, or 0 when even one cell keeps more.
  Result<std::uint32_t> choose_resolution(std::uint64_t limit) {
    const double side = domain_side();
    constexpr std::uint32_t kMaxResolution = 1u << 16;
    const double guess = survey_.area > 0.0 ? side * std::sqrt(static_cast<double>(limit) / (3.0 * survey_.area)) : 8.0;
    std::uint32_t lo = 0, hi = kMaxResolution + 1;  // lo: feasible (0: none yet), hi: infeasible
    auto g = static_cast<std::uint32_t>(std::clamp(guess, 1.0, static_cast<double>(kMaxResolution)));
    // next_search_resolution's steps; stop within 15% below the limit (as
    // search_grid_resolution, at most 10 counts). A count abandoned past 2 x limit distinct
    // triples steps as a count of 4 x limit would.
    for (int evaluation = 0; evaluation < 10 && hi - lo > 1; ++evaluation) {
      g = std::clamp(g, lo + 1, hi - 1);
      auto counted = count_triangles(g, limit);
      if (!counted.ok()) return counted.status();
      const std::optional<std::uint64_t> count = counted.value();
      if (count && *count <= limit) {
        lo = g;
        if (static_cast<double>(*count) >= 0.85 * static_cast<double>(limit)) break;
      } else {
        hi = g;
      }
      g = next_search_resolution(g, static_cast<std::size_t>(count ? *count : 4 * limit),
                                 static_cast<std::size_t>(limit), lo, hi);
    }
    if (lo == 0 && hi > 1) {  // the search stopped above g = 1: the coarsest grid decides
      auto coarsest = count_triangles(1, limit);
      if (!coarsest.ok()) return coarsest.status();
      if (coarsest.value() && *coarsest.value() <= limit) lo = 1;
    }
    return lo;
  }

  // LOD 1 at resolution g: clusters' quadrics and attribute sums and the candidate triangles in
  // one pass, the clusters' best own vertices in a second, then the mesh.
  Result<NodeMesh> cluster(std::uint32_t g, std::uint64_t limit) {
    const GridDomain grid = make_domain(g);
    const GridCellKeys cells(grid, origin_);
    constexpr std::size_t q3 = quadric_doubles(3);
    std::unordered_map<std::uint64_t, std::uint32_t> cluster_of;
    std::vector<std::uint64_t> keys;       // per cluster
    std::vector<double> quadric, sum, best;
    AttributeWedges wedges(layout_);
    std::vector<std::uint32_t> corners;
    // locked vertex records (bit-identical in the output), by their bits
    std::unordered_map<std::string, std::uint32_t> locked_record_of;
    std::vector<float> locked_records;
    struct Candidate {
      TripleSources sources;
      std::array<std::uint32_t, 3> like{};      // output vertex refs of the first source winding
      std::array<std::uint32_t, 3> opposite{};  // like the sorted triple, and of the first the other way
    };
    constexpr std::uint32_t kLockedRef = 1u << 31;
    FlatHashMap<3> candidate_of(2 * limit);
    std::vector<Candidate> candidates;
    const std::size_t stride = layout_.floats();

    auto cluster_id = [&](const float* vertex) {
      const std::uint64_t key = key_of(cells, vertex);
      auto [it, inserted] = cluster_of.try_emplace(key, static_cast<std::uint32_t>(keys.size()));
      if (inserted) {
        keys.push_back(key);
        quadric.resize(quadric.size() + q3, 0.0);
        sum.resize(sum.size() + 3, 0.0);
        corners.push_back(0);
        best.insert(best.end(), {0.0, 0.0, 0.0, std::numeric_limits<double>::infinity()});
      }
      return it->second;
    };
    // an unlocked corner's ref is its wedge
    auto vertex_ref = [&](std::uint32_t cluster, std::uint32_t wedge, const float* vertex) {
      if (!(keys[cluster] & kLockedKey)) return wedge;
      std::string bits(reinterpret_cast<const char*>(vertex), layout_.bytes());
      auto [it, inserted] = locked_record_of.try_emplace(std::move(bits), static_cast<std::uint32_t>(locked_records.size() / stride));
      if (inserted) locked_records.insert(locked_records.end(), vertex, vertex + stride);
      return kLockedRef | it->second;
    };

    // pass 1: quadrics, sums, candidates
    OCTOLOD_RETURN_IF_ERROR(for_each_chunk(records_, record_bytes_, options_.chunk_triangles,
                                           [&](std::span<const std::byte> chunk) -> Status {
      for (std::size_t r = 0; r < chunk.size() / record_bytes_; ++r) {
        const Corners c = load_corners(chunk.data() + r * record_bytes_, layout_);
        std::array<std::uint32_t, 3> id;
        for (std::size_t k = 0; k < 3; ++k) id[k] = cluster_id(c.vertex[k].data());
        const float* p[3] = {c.vertex[0].data(), c.vertex[1].data(), c.vertex[2].data()};
        const std::array<double, 3> normal = triangle_normal(p[0], p[1], p[2]);
        const double a = triangle_area(normal);
        double plane[q3] = {};
        const double p0[3] = {double(p[0][0]) - origin_[0], double(p[0][1]) - origin_[1], double(p[0][2]) - origin_[2]};
        if (a > 0.0) plane_quadric(normal.data(), p0, a, plane);
        std::array<std::uint32_t, 3> wedge{AttributeWedges::kNone, AttributeWedges::kNone, AttributeWedges::kNone};
        for (std::size_t k = 0; k < 3; ++k) {
          const std::uint32_t cl = id[k];
          if (keys[cl] & kLockedKey) continue;
          wedge[k] = wedges.wedge_of(cl, p[k] + 3);
          ++corners[cl];
          for (std::size_t i = 0; i < 3; ++i) sum[cl * 3 + i] += double(p[k][i]) - origin_[i];
          if (!(a > 0.0)) continue;
          add_quadric(3, &quadric[cl * q3], plane);
          wedges.add(wedge[k], a, p[k] + 3);
        }
        if (id[0] == id[1] || id[1] == id[2] || id[0] == id[2]) continue;
        const std::array<std::uint32_t, 3> sorted = sorted_triple(id[0], id[1], id[2]);
        const bool even = winds_like_sorted(id[0], id[1], id[2]);
        // the count pass at g saw the same distinct triples (its keys, one to one with the ids)
        assert((candidates.size() < 2 * limit || candidate_of.find(sorted) != FlatHashMap<3>::kMissing) &&
               "more cluster triples than the count pass at this resolution found");
        bool inserted = false;
        const std::uint32_t index = candidate_of.find_or_insert(sorted, static_cast<std::uint32_t>(candidates.size()), inserted);
        if (inserted) candidates.emplace_back();
        Candidate& candidate = candidates[index];
        if (candidate.sources.add(even, normal)) {
          std::array<std::uint32_t, 3>& refs = even ? candidate.like : candidate.opposite;
          for (std::size_t k = 0; k < 3; ++k) refs[k] = vertex_ref(id[k], wedge[k], p[k]);
        }
      }
      return {};
    }));

    // pass 2: each unlocked cluster's own vertex with the least quadric error
    OCTOLOD_RETURN_IF_ERROR(for_each_chunk(records_, record_bytes_, options_.chunk_triangles,
                                           [&](std::span<const std::byte> chunk) -> Status {
      for (std::size_t r = 0; r < chunk.size() / record_bytes_; ++r) {
        const Corners c = load_corners(chunk.data() + r * record_bytes_, layout_);
        for (std::size_t k = 0; k < 3; ++k) {
          const std::uint32_t cl = cluster_of.at(key_of(cells, c.vertex[k].data()));
          if (keys[cl] & kLockedKey) continue;
          double x[3];
          for (std::size_t i = 0; i < 3; ++i) x[i] = double(c.vertex[k][i]) - origin_[i];
          const double error = evaluate_quadric(3, &quadric[cl * q3], x);
          double* b = &best[cl * 4];
          if (error < b[3]) std::copy(x, x + 3, b), b[3] = error;
        }
      }
      return {};
    }));

    // representatives: per cluster a position from its quadric, per wedge its attributes
    std::vector<double> position(keys.size() * 3);
    for (std::size_t cl = 0; cl < keys.size(); ++cl) {
      if (keys[cl] & kLockedKey) continue;
      double mean[3];
      for (std::size_t i = 0; i < 3; ++i) mean[i] = sum[cl * 3 + i] / corners[cl];
      place_representative(&quadric[cl * q3], mean, grid_cell_box(grid, keys[cl]), &best[cl * 4], &position[cl * 3]);
    }
    std::vector<float> representative(wedges.size() * stride);
    for (std::uint32_t w = 0; w < wedges.size(); ++w) {
      double v[kMaxQuadricDim] = {};
      wedges.attributes(w, v + 3);
      const double up[3] = {0.0, 0.0, 1.0};
      finish_attributes(layout_, up, v + 3);
      float* out = &representative[w * stride];
      for (std::size_t i = 0; i < 3; ++i) out[i] = static_cast<float>(position[wedges.cluster(w) * 3 + i] + origin_[i]);
      for (std::size_t i = 3; i < stride; ++i) out[i] = static_cast<float>(v[i]);
    }

    // output: kept_copies per candidate, oriented like their sources (a two-sided pair: the
    // copy facing like the sources that wind like the sorted triple, with the first such
    // source's wedges, and the first opposite source's wound against it), vertices in order of
    // first use
    NodeMesh lod;
    lod.layout = layout_;
    std::unordered_map<std::uint32_t, std::uint32_t> output_of_ref;
    auto record_of = [&](std::uint32_t ref) {
      return ref & kLockedRef ? &locked_records[(ref & ~kLockedRef) * stride] : &representative[ref * stride];
    };
    std::vector<std::uint32_t> kept;  // one candidate's kept corners (refs)
    for (const Candidate& candidate : candidates) {
      kept.clear();
      append_kept_triangles(candidate.sources, candidate.like, candidate.opposite, record_of, kept);
      for (std::uint32_t r : kept) {
        auto [it, inserted] = output_of_ref.try_emplace(r, static_cast<std::uint32_t>(lod.vertex_count()));
        if (inserted) {
          const float* record = record_of(r);
          lod.vertices.insert(lod.vertices.end(), record, record + stride);
        }
        lod.indices.push_back(it->second);
      }
    }
    rewind_inside_out(lod);
    return lod;
  }

  // max over chunks of hausdorff_upper_bound(chunk, lod): the one-sided distance from the input.
  Result<double> error_bound(const NodeMesh& lod) {
    double error = 0.0;
    OCTOLOD_RETURN_IF_ERROR(for_each_chunk(records_, record_bytes_, options_.chunk_triangles,
                                           [&](std::span<const std::byte> chunk) -> Status {
      indexer_.index(chunk, layout_, mesh_);
      error = std::max(error, hausdorff_upper_bound(mesh_, lod));
      return {};
    }));
    mesh_ = {};
    return error;
  }

  // LOD 0: every chunk's vertices, then every chunk's indices (offset by the earlier chunks'
  // vertices), in two passes that index the same chunks.
  Result<std::uint64_t> write_lod0(const fs::path& path) {
    auto writer = NodeFileWriter::create(path, layout_, static_cast<std::uint32_t>(survey_.vertices),
                                         static_cast<std::uint32_t>(3 * survey_.triangles), survey_.bounds);
    if (!writer.ok()) return writer.status();
    OCTOLOD_RETURN_IF_ERROR(for_each_chunk(records_, record_bytes_, options_.chunk_triangles,
                                           [&](std::span<const std::byte> chunk) {
      indexer_.index(chunk, layout_, mesh_);
      return writer->append_vertices(mesh_.vertices);
    }));
    std::uint32_t base = 0;
    OCTOLOD_RETURN_IF_ERROR(for_each_chunk(records_, record_bytes_, options_.chunk_triangles,
                                           [&](std::span<const std::byte> chunk) {
      indexer_.index(chunk, layout_, mesh_);
      for (std::uint32_t& index : mesh_.indices) index += base;
      base += static_cast<std::uint32_t>(mesh_.vertex_count());
      return writer->append_indices(mesh_.indices);
    }));
    mesh_ = {};
    return writer->finish();
  }

  const Survey& surveyed() const { return survey_; }

  void set_origin() {
    for (std::size_t i = 0; i < 3; ++i)
      origin_[i] = 0.5 * (static_cast<double>(options_.cell.min[i]) + options_.cell.max[i]);
  }

 private:
  static constexpr std::uint64_t kLockedKey = 1ull << 63;

  GridDomain make_domain(std::uint32_t g) const {
    return make_grid_domain(options_.cell, survey_.bounds, origin_, g);
  }

  double domain_side() const {
    Bounds domain = options_.cell;
    domain.extend(survey_.bounds);
    return std::max({static_cast<double>(domain.max[0]) - domain.min[0],
                     static_cast<double>(domain.max[1]) - domain.min[1],
                     static_cast<double>(domain.max[2]) - domain.min[2]});
  }

  // A corner's cluster: its locked position's id, else its grid cell.
  std::uint64_t key_of(const GridCellKeys& cells, const float* vertex) const {
    if (locked_count_ > 0) {
      const std::uint32_t id = locked_->find(position_bits(vertex));
      if (id != FlatHashMap<3>::kMissing) return kLockedKey | id;
    }
    return cells.key(vertex);
  }

  // Triangles the clustering at g keeps (build_clustered_mesh's rule), or nothing when the
  // distinct cluster triples pass 2 x limit (memory stays bounded; the resolution is too fine).
  Result<std::optional<std::uint64_t>> count_triangles(std::uint32_t g, std::uint64_t limit) {
    const GridCellKeys cells(make_domain(g), origin_);
    KeptTriangleCounter<6> counter(static_cast<std::size_t>(2 * limit));
    bool over = false;
    OCTOLOD_RETURN_IF_ERROR(for_each_chunk(records_, record_bytes_, options_.chunk_triangles,
                                           [&](std::span<const std::byte> chunk) -> Status {
      for (std::size_t r = 0; r < chunk.size() / record_bytes_ && !over; ++r) {
        const Corners c = load_corners(chunk.data() + r * record_bytes_, layout_);
        const std::array<std::uint64_t, 3> id{key_of(cells, c.vertex[0].data()), key_of(cells, c.vertex[1].data()),
                                              key_of(cells, c.vertex[2].data())};
        std::array<std::uint64_t, 3> key = id;
        std::sort(key.begin(), key.end());
        if (key[0] == key[1] || key[1] == key[2]) continue;
        KeptTriangleCounter<6>::Key words;
        for (std::size_t k = 0; k < 3; ++k) {
          words[2 * k] = static_cast<std::uint32_t>(key[k] >> 32);
          words[2 * k + 1] = static_cast<std::uint32_t>(key[k]);
        }
        if (counter.distinct() >= 2 * limit && !counter.contains(words)) {
          over = true;
          break;
        }
        counter.add(words, winds_like_sorted(id[0], id[1], id[2]));
      }
      return {};
    }));
    if (over) return std::optional<std::uint64_t>{};
    return std::optional<std::uint64_t>{counter.kept()};
  }

  fs::path records_;
  const StreamedLeafOptions& options_;
  VertexLayout layout_;
  std::size_t record_bytes_;
  NodeIndexer indexer_;
  NodeMesh mesh_;  // the chunk being indexed
  Survey survey_;
  std::array<double, 3> origin_{};
  std::unique_ptr<FlatHashMap<3>> locked_;  // locked position -> id
  std::size_t locked_count_ = 0;
};

}  // namespace

LeafRecordSpill::LeafRecordSpill(fs::path work_dir, VertexLayout layout, std::size_t buffer_bytes,
                                 std::uint64_t sort_budget_bytes)
    : work_dir_(std::move(work_dir)),
      layout_(layout),
      buffer_bytes_(buffer_bytes),
      sort_budget_bytes_(sort_budget_bytes) {}

Status LeafRecordSpill::append(std::span<const std::byte> records) {
  if (!writer_) {
    file_ = make_temp_file(work_dir_, "leaf-spill");
    auto writer = RecordWriter::create(file_.path(), soup_record_bytes(layout_), buffer_bytes_);
    if (!writer.ok()) return writer.status();
    writer_.emplace(std::move(writer).value());
  }
  const std::size_t record_bytes = soup_record_bytes(layout_);
  for (std::size_t i = 0; i < records.size() && in_order_; i += record_bytes) {
    const auto id = static_cast<std::uint32_t>(load_soup_triangle_id(records.data() + i, layout_));
    in_order_ = !any_ || id > last_id_;
    last_id_ = id;
    any_ = true;
  }
  return writer_->append(records.data(), records.size() / record_bytes);
}

Result<TempFile> LeafRecordSpill::finish() {
  assert(writer_ && "LeafRecordSpill::finish without records");
  OCTOLOD_RETURN_IF_ERROR(writer_->finish());
  writer_.reset();
  const bool in_order = in_order_;
  in_order_ = true;
  any_ = false;
  if (in_order) return std::move(file_);  // the usual case on the in-memory octree
  TempFile sorted = make_temp_file(work_dir_, "leaf");
  SortOptions sort;
  sort.memory_budget_bytes = sort_budget_bytes_;
  sort.work_dir = work_dir_;
  sort.threads = 1;
  const std::size_t record_bytes = soup_record_bytes(layout_);
  auto stats = sort_records(file_.path(), sorted.path(), record_bytes,
                            sort_key_u32_at(soup_triangle_id_offset(layout_), record_bytes), sort);
  file_.remove();
  if (!stats.ok()) return stats.status();
  return sorted;
}

Result<StreamedLeafLods> build_streamed_leaf(const fs::path& records, const fs::path& root,
                                             const std::string& dir,
                                             const StreamedLeafOptions& options) {
  // The LODs from every face once (repeated_records.h); LOD 0 keeps the records as they are.
  std::optional<TempFile> once;
  if (options.build_lods) {
    auto without = without_repeated_records(records, options.layout, options.work_dir, options.sort_budget_bytes);
    if (!without.ok()) return without.status();
    once = std::move(without).value();
  }
  StreamedLeafBuilder builder(once ? once->path() : records, options);
  builder.set_origin();
  TempFile edges = make_temp_file(options.work_dir, "leaf-edges");
  TempFile sorted_edges = make_temp_file(options.work_dir, "leaf-edges-sorted");
  OCTOLOD_RETURN_IF_ERROR(builder.survey(options.build_lods ? &edges.path() : nullptr));

  StreamedLeafLods result;
  if (!options.merged_children) {
    std::optional<StreamedLeafBuilder> with_repeats;
    if (once) {
      with_repeats.emplace(records, options);
      OCTOLOD_RETURN_IF_ERROR(with_repeats->survey(nullptr));
    }
    StreamedLeafBuilder& lod0 = with_repeats ? *with_repeats : builder;
    const std::string file = lod_file_name(dir, 0);
    auto bytes = lod0.write_lod0(root / file);
    if (!bytes.ok()) return bytes.status();
    const Survey& survey = lod0.surveyed();
    result.lod0.triangles = static_cast<std::uint32_t>(survey.triangles);
    result.lod0.vertices = static_cast<std::uint32_t>(survey.vertices);
    result.lod0.bytes = bytes.value();
    result.lod0.file = file;
    result.lod0_bounds = survey.bounds;
    if (!options.build_lods) return result;
  }
  const Survey& survey = builder.surveyed();

  OCTOLOD_RETURN_IF_ERROR(builder.find_boundary_positions(edges.path(), sorted_edges.path()));
  const auto ratio_limit = static_cast<std::uint64_t>(std::floor(static_cast<double>(survey.triangles) * options.lod.reduction));
  const std::uint64_t limit = std::min<std::uint64_t>(options.max_lod1_triangles, ratio_limit);
  if (limit == 0) return result;
  auto g = builder.choose_resolution(limit);
  if (!g.ok()) return g.status();
  if (g.value() == 0) return result;  // the locked boundary alone keeps more than the limit
  auto lod1 = builder.cluster(g.value(), limit);
  if (!lod1.ok()) return lod1.status();
  if (lod1->triangle_count() == 0) return result;
  auto error = builder.error_bound(lod1.value());
  if (!error.ok()) return error.status();

  LodOptions chain = options.lod;
  chain.include_input = true;  // LOD 1 heads the chain
  if (!options.merged_children) chain.max_lods = std::max<std::uint32_t>(1, options.lod.max_lods - 1);
  auto lods = build_lods(std::move(lod1).value(), options.input_error + error.value(), options.cell, chain);
  if (!lods.ok()) return lods.status();
  result.coarser = std::move(lods).value();
  return result;
}

}  // namespace octolod::bake
