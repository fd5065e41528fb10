// SampleStream: batches a shape generator's output (see shape_generator.h) into a fixed buffer,
// and write_sample_ply() pipes it into a PlyWriter running on a thread of its own, so any
// triangle count streams in a few batches' worth of memory while generation and encoding overlap.
#include "octolod/samplegen/sample_generator.h"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <condition_variable>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
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
    case Shape::tube:
      return "tube";
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
    case Shape::tube:
      return make_tube(spec);
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
  // Vertices [vertices_done_, + count) into the buffer. With threads_ > 1 the range is cut into
  // fixed chunks that threads claim one at a time, so a thread slowed down by others (the
  // background writer) does not hold the batch up; each chunk's bytes do not depend on who
  // computes it.
  void generate_vertices(std::size_t count) {
    constexpr std::size_t kChunk = 1024;  // vertices: ~0.1-0.5 ms of work, far above thread costs
    const std::size_t chunks = (count + kChunk - 1) / kChunk;
    const std::size_t floats = spec_.layout.floats();
    std::atomic<std::size_t> next_chunk{0};
    auto work = [&] {
      for (std::size_t c; (c = next_chunk.fetch_add(1)) < chunks;) {
        const std::size_t begin = c * kChunk, end = std::min(count, begin + kChunk);
        generator_->vertices(vertices_done_ + begin, end - begin,
                             vertex_buffer_.data() + begin * floats);
      }
    };
    std::vector<std::jthread> helpers;
    for (std::size_t t = 1; t < std::min<std::size_t>(threads_, chunks); ++t)
      helpers.emplace_back(work);
    work();
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

namespace {

// A batch the pipeline owns: the stream's batch is only valid until its next().
struct OwnedBatch {
  SampleBatch::Kind kind = SampleBatch::Kind::end;
  std::vector<float> vertices;
  std::vector<std::uint32_t> triangles;
};

// Writes batches on a thread of its own while the caller generates the next one, through a
// one-slot mailbox; buffers circulate by swapping, so three batches exist at most.
class BackgroundWriter {
 public:
  explicit BackgroundWriter(PlyWriter& writer) : writer_(writer), thread_([this] { run(); }) {}
  ~BackgroundWriter() { (void)close(); }
  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;

  // Hands `batch` over and leaves a spent buffer in its place; false once a write failed.
  bool put(OwnedBatch& batch) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return !full_ || !failure_.ok(); });
    if (!failure_.ok()) return false;
    std::swap(slot_, batch);
    full_ = true;
    changed_.notify_all();
    return true;
  }

  // Waits until everything handed over is written; the first write error, if any.
  Status close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
      changed_.notify_all();
    }
    if (thread_.joinable()) thread_.join();
    return failure_;
  }

 private:
  void run() {
    OwnedBatch work;
    for (;;) {
      {
        std::unique_lock lock(mutex_);
        changed_.wait(lock, [&] { return full_ || closed_; });
        if (!full_) return;  // closed and drained
        std::swap(slot_, work);
        full_ = false;
        changed_.notify_all();
      }
      const Status status = work.kind == SampleBatch::Kind::vertices
                                ? writer_.write_vertices(work.vertices)
                                : writer_.write_triangles(work.triangles);
      if (!status.ok()) {
        std::lock_guard lock(mutex_);
        failure_ = status;
        changed_.notify_all();
        return;
      }
    }
  }

  PlyWriter& writer_;
  std::mutex mutex_;
  std::condition_variable changed_;
  OwnedBatch slot_;
  bool full_ = false;
  bool closed_ = false;
  Status failure_;
  std::thread thread_;  // last: starts after everything it uses exists
};

}  // namespace

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
  std::string command = "octolod sample --shape " + std::string(to_string(spec.shape)) + " --triangles " +
                        std::to_string(spec.triangles) + " --attributes " + attributes + " --seed " +
                        std::to_string(spec.seed);
  if (spec.offset != std::array<double, 3>{0.0, 0.0, 0.0}) {
    options.position_origin = spec.offset;
    char text[96];
    std::snprintf(text, sizeof text, " --offset %.17g,%.17g,%.17g", spec.offset[0], spec.offset[1], spec.offset[2]);
    command += text;
  }
  if (!spec.texture_file.empty()) command += " --texture";
  options.comments.push_back(std::move(command));
  if (!spec.texture_file.empty()) options.comments.push_back("TextureFile " + spec.texture_file);
  Result<std::unique_ptr<PlyWriter>> writer =
      PlyWriter::create(path, options, counts.vertices, counts.triangles);
  if (!writer.ok()) return writer.status();

  const std::uint64_t total = counts.vertices + counts.triangles;
  std::uint64_t done = 0;
  BackgroundWriter background(*writer.value());
  OwnedBatch owned;
  for (SampleBatch batch = stream.value()->next(); batch.kind != SampleBatch::Kind::end;
       batch = stream.value()->next()) {
    owned.kind = batch.kind;
    owned.vertices.assign(batch.vertices.begin(), batch.vertices.end());
    owned.triangles.assign(batch.triangles.begin(), batch.triangles.end());
    if (!background.put(owned)) break;  // close() reports the error
    done += batch.vertices.size() / spec.layout.floats() + batch.triangles.size() / 3;
    if (progress) progress(done, total);
  }
  OCTOLOD_RETURN_IF_ERROR(background.close());
  return writer.value()->finish();
}

Result<Shape> parse_shape(std::string_view text) {
  for (Shape shape : {Shape::rock, Shape::terrain, Shape::city, Shape::tube})
    if (text == to_string(shape)) return shape;
  return usage_error("unknown shape '" + std::string(text) +
                     "' (expected rock, terrain, city or tube)");
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

Result<NodeMesh> generate_sample_mesh(const SampleSpec& spec) {
  Result<std::unique_ptr<SampleStream>> stream = SampleStream::create(spec);
  if (!stream.ok()) return stream.status();
  NodeMesh mesh;
  mesh.layout = spec.layout;
  for (SampleBatch batch = stream.value()->next(); batch.kind != SampleBatch::Kind::end;
       batch = stream.value()->next()) {
    mesh.vertices.insert(mesh.vertices.end(), batch.vertices.begin(), batch.vertices.end());
    mesh.indices.insert(mesh.indices.end(), batch.triangles.begin(), batch.triangles.end());
  }
  return mesh;
}

}  // namespace octolod::samplegen
