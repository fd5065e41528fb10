// SampleStream: batches a shape generator's sequential output (see shape_generator.h) into a
// fixed buffer, and write_sample_ply() pipes it into a PlyWriter, so any triangle count streams
// in about SampleStreamOptions::batch_bytes of memory.
#include "octolod/samplegen/sample_generator.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "octolod/formats/ply_writer.h"
#include "shape_generator.h"

namespace octolod::samplegen {

std::string_view to_string(Shape shape) {
  switch (shape) {
    case Shape::rock:
      return "rock";
    case Shape::terrain:
      return "terrain";
    case Shape::city:
      return "city";
  }
  return "unknown";
}

namespace {

Status check_spec(const SampleSpec& spec) {
  if (spec.triangles < kMinTriangles || spec.triangles > kMaxTriangles)
    return usage_error("sample triangle count " + std::to_string(spec.triangles) +
                       " out of range [" + std::to_string(kMinTriangles) + ", " +
                       std::to_string(kMaxTriangles) + "]");
  return {};
}

std::unique_ptr<ShapeGenerator> make_generator(const SampleSpec& spec) {
  switch (spec.shape) {
    case Shape::rock:
      return make_rock(spec);
    case Shape::terrain:
      return make_terrain(spec);
    case Shape::city:
      return make_city(spec);
  }
  return make_rock(spec);
}

}  // namespace

Result<SampleCounts> sample_counts(const SampleSpec& spec) {
  OCTOLOD_RETURN_IF_ERROR(check_spec(spec));
  return make_generator(spec)->counts();
}

class SampleStream::Impl {
 public:
  Impl(const SampleSpec& spec, const SampleStreamOptions& options)
      : spec_(spec), generator_(make_generator(spec)), counts_(generator_->counts()) {
    const std::size_t bytes = std::max<std::size_t>(options.batch_bytes, 4096);
    batch_vertices_ = std::max<std::size_t>(1, bytes / spec.layout.bytes());
    batch_triangles_ = bytes / 12;
    vertex_buffer_.resize(batch_vertices_ * spec.layout.floats());
    threads_ = std::max(1u, options.threads);
  }

  SampleBatch next() {
    SampleBatch batch;
    if (vertices_done_ < counts_.vertices) {
      const auto count = static_cast<std::size_t>(
          std::min<std::uint64_t>(batch_vertices_, counts_.vertices - vertices_done_));
      generate_vertices(count);
      batch.kind = SampleBatch::Kind::vertices;
      batch.first = vertices_done_;
      batch.vertices = {vertex_buffer_.data(), count * spec_.layout.floats()};
      vertices_done_ += count;
    } else if (triangles_done_ < counts_.triangles) {
      const auto count = static_cast<std::size_t>(
          std::min<std::uint64_t>(batch_triangles_, counts_.triangles - triangles_done_));
      if (triangle_buffer_.empty()) {
        // The vertex phase is over: trade its buffer for the triangle one.
        std::vector<float>().swap(vertex_buffer_);
        triangle_buffer_.resize(batch_triangles_ * 3);
      }
      generator_->next_triangles(count, triangle_buffer_.data());
      batch.kind = SampleBatch::Kind::triangles;
      batch.first = triangles_done_;
      batch.triangles = {triangle_buffer_.data(), count * 3};
      triangles_done_ += count;
    }
    return batch;
  }

  const SampleSpec& spec() const { return spec_; }
  const SampleCounts& counts() const { return counts_; }

 private:
  // Vertices [vertices_done_, + count) into the buffer, split over threads_ when worth it.
  void generate_vertices(std::size_t count) {
    constexpr std::size_t kMinPerThread = 2048;  // below this, a thread costs more than it saves
    const std::size_t parts = std::clamp<std::size_t>(count / kMinPerThread, 1, threads_);
    const std::size_t floats = spec_.layout.floats();
    std::vector<std::jthread> helpers;
    for (std::size_t p = 1; p < parts; ++p) {
      const std::size_t begin = count * p / parts, end = count * (p + 1) / parts;
      helpers.emplace_back([this, begin, end, floats] {
        generator_->vertices(vertices_done_ + begin, end - begin,
                             vertex_buffer_.data() + begin * floats);
      });
    }
    generator_->vertices(vertices_done_, count / parts, vertex_buffer_.data());
  }

  SampleSpec spec_;
  std::unique_ptr<ShapeGenerator> generator_;
  SampleCounts counts_;
  std::size_t batch_vertices_ = 0;
  std::size_t batch_triangles_ = 0;
  unsigned threads_ = 1;
  std::vector<float> vertex_buffer_;            // during the vertex phase
  std::vector<std::uint32_t> triangle_buffer_;  // during the triangle phase
  std::uint64_t vertices_done_ = 0;
  std::uint64_t triangles_done_ = 0;
};

Result<std::unique_ptr<SampleStream>> SampleStream::create(const SampleSpec& spec,
                                                           const SampleStreamOptions& options) {
  OCTOLOD_RETURN_IF_ERROR(check_spec(spec));
  return std::unique_ptr<SampleStream>(new SampleStream(std::make_unique<Impl>(spec, options)));
}

SampleStream::SampleStream(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SampleStream::~SampleStream() = default;
const SampleSpec& SampleStream::spec() const { return impl_->spec(); }
const SampleCounts& SampleStream::counts() const { return impl_->counts(); }
SampleBatch SampleStream::next() { return impl_->next(); }

Status write_sample_ply(const SampleSpec& spec, const std::filesystem::path& path, PlyFormat format,
                        const SampleProgress& progress, const SampleStreamOptions& stream_options) {
  Result<std::unique_ptr<SampleStream>> stream = SampleStream::create(spec, stream_options);
  if (!stream.ok()) return stream.status();
  const SampleCounts counts = stream.value()->counts();

  PlyWriteOptions options;
  options.format = format;
  options.layout = spec.layout;
  options.color_type = PlyColorType::uchar;
  // The command that reproduces the file byte for byte.
  const std::string layout = spec.layout.describe();
  const std::string attributes = layout == "position" ? "none" : layout.substr(9);  // "position,"
  options.comments.push_back("octolod sample --shape " + std::string(to_string(spec.shape)) +
                             " --triangles " + std::to_string(spec.triangles) + " --attributes " +
                             attributes + " --seed " + std::to_string(spec.seed));
  Result<std::unique_ptr<PlyWriter>> writer =
      PlyWriter::create(path, options, counts.vertices, counts.triangles);
  if (!writer.ok()) return writer.status();

  const std::uint64_t total = counts.vertices + counts.triangles;
  std::uint64_t done = 0;
  for (SampleBatch batch = stream.value()->next(); batch.kind != SampleBatch::Kind::end;
       batch = stream.value()->next()) {
    if (batch.kind == SampleBatch::Kind::vertices) {
      OCTOLOD_RETURN_IF_ERROR(writer.value()->write_vertices(batch.vertices));
      done += batch.vertices.size() / spec.layout.floats();
    } else {
      OCTOLOD_RETURN_IF_ERROR(writer.value()->write_triangles(batch.triangles));
      done += batch.triangles.size() / 3;
    }
    if (progress) progress(done, total);
  }
  return writer.value()->finish();
}

Result<Shape> parse_shape(std::string_view text) {
  for (Shape shape : {Shape::rock, Shape::terrain, Shape::city})
    if (text == to_string(shape)) return shape;
  return usage_error("unknown shape '" + std::string(text) + "' (expected rock, terrain or city)");
}

Result<std::uint64_t> parse_triangle_count(std::string_view text) {
  std::string quoted;  // built in place: GCC 12 -O3 misreports "'" + std::string as -Wrestrict
  quoted.append("'").append(text).append("'");
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || text.empty())
    return usage_error("not a triangle count: " + quoted + " (expected e.g. 200000, 2e5, 20M)");
  const std::string_view suffix(end, static_cast<std::size_t>(text.data() + text.size() - end));
  double scale = 1;
  if (suffix == "K" || suffix == "k")
    scale = 1e3;
  else if (suffix == "M" || suffix == "m")
    scale = 1e6;
  else if (suffix == "G" || suffix == "g")
    scale = 1e9;
  else if (!suffix.empty())
    return usage_error("unknown suffix in triangle count " + quoted + " (use K, M or G)");
  const double count = std::floor(value * scale + 0.5);
  if (!(count >= static_cast<double>(kMinTriangles) && count <= static_cast<double>(kMaxTriangles)))
    return usage_error("triangle count " + quoted + " out of range [" +
                       std::to_string(kMinTriangles) + ", " + std::to_string(kMaxTriangles) + "]");
  return static_cast<std::uint64_t>(count);
}

Result<VertexLayout> parse_attributes(std::string_view text) {
  VertexLayout layout;
  if (text.empty() || text == "none") return layout;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t comma = std::min(text.find(',', begin), text.size());
    const std::string_view name = text.substr(begin, comma - begin);
    if (name == "normal")
      layout.normal = true;
    else if (name == "color" || name == "colour")
      layout.color = true;
    else if (name == "uv")
      layout.uv = true;
    else
      return usage_error("unknown attribute '" + std::string(name) + "' in '" + std::string(text) +
                         "' (expected a comma-separated subset of normal,color,uv)");
    begin = comma + 1;
  }
  return layout;
}

}  // namespace octolod::samplegen
