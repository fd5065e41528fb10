// The triangle soup stage (seed 3.3, 4.2, Table 4.1): split with the window pass and, for the
// far triangles, three sort + dereference passes out of core, or one gather from the
// in-memory vertices when they fit. See
// octolod/bake/soup.h for the contract; this file decides the path and divides the budget.
#include "octolod/bake/soup.h"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <chrono>
#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <utility>

#include "dereference.h"
#include "page_array.h"
#include "octolod/formats/ply_reader.h"
#include "record_file.h"
#include "split.h"

namespace octolod::bake {
namespace {

// PlyReader's fixed file buffer on top of PlyReadOptions::buffer_bytes (ply_reader.h).
constexpr std::uint64_t kPlyFileBuffer = 64 * 1024;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The next pass's sort as an output: records are written straight into its run buffer.
class SorterOutput final : public RecordOutput {
 public:
  explicit SorterOutput(RecordSorter& sorter) : sorter_(sorter) {}
  Result<std::span<std::byte>> reserve(std::size_t max_records) override {
    return sorter_.reserve(max_records);
  }
  Status commit(std::size_t records) override {
    sorter_.commit(records);
    return {};
  }

 private:
  RecordSorter& sorter_;
};

// The soup's destination: the caller's SoupOptions::sink (records batched in `io` bytes) or a
// new soup file (written through a RecordWriter of `io` bytes).
class SoupOutput final : public RecordOutput {
 public:
  static Result<std::unique_ptr<SoupOutput>> open(const SoupOptions& options, VertexLayout layout,
                                                  std::size_t io, TempFile& file) {
    const std::size_t record_bytes = soup_record_bytes(layout);
    auto out = std::unique_ptr<SoupOutput>(new SoupOutput(record_bytes));
    if (options.sink) {
      out->sink_ = &options.sink;
      out->batch_records_ = std::max<std::size_t>(1, io / record_bytes);
      out->batch_ = PageArray<std::byte>(out->batch_records_ * record_bytes);
      return out;
    }
    file = make_temp_file(options.work_dir, "soup");
    auto writer = RecordWriter::create(file.path(), record_bytes, io);
    if (!writer.ok()) return writer.status();
    out->writer_.emplace(std::move(writer).value());
    return out;
  }

  Result<std::span<std::byte>> reserve(std::size_t max_records) override {
    if (writer_) return writer_->reserve(max_records);
    return std::span<std::byte>(batch_.get(), std::min(max_records, batch_records_) * record_bytes_);
  }
  Status commit(std::size_t records) override {
    if (writer_) {
      writer_->commit(records);
      return {};
    }
    if (records == 0) return {};
    return (*sink_)(std::span<const std::byte>(batch_.get(), records * record_bytes_));
  }
  Status finish() { return writer_ ? writer_->finish() : Status{}; }

 private:
  explicit SoupOutput(std::size_t record_bytes) : record_bytes_(record_bytes) {}

  std::size_t record_bytes_;
  std::optional<RecordWriter> writer_;
  const std::function<Status(std::span<const std::byte>)>* sink_ = nullptr;
  PageArray<std::byte> batch_;
  std::size_t batch_records_ = 0;
};

// Reports `stage` progress as records are committed to another output.
class ProgressOutput final : public RecordOutput {
 public:
  ProgressOutput(RecordOutput& inner, std::function<void(std::uint64_t done)> report)
      : inner_(inner), report_(std::move(report)) {}
  Result<std::span<std::byte>> reserve(std::size_t max_records) override {
    return inner_.reserve(max_records);
  }
  Status commit(std::size_t records) override {
    OCTOLOD_RETURN_IF_ERROR(inner_.commit(records));
    done_ += records;
    report_(done_);
    return {};
  }

 private:
  RecordOutput& inner_;
  std::function<void(std::uint64_t)> report_;
  std::uint64_t done_ = 0;
};

// Soup records in triangle order get each corner's values from the corner file the split wrote
// (PlyInfo::corners: 3 * corners.floats() floats per triangle, triangle order) on their way to
// `inner`.
class CornerValuesOutput final : public RecordOutput {
 public:
  CornerValuesOutput(RecordOutput& inner, VertexLayout layout, CornerAttributes corners, RecordReader values)
      : inner_(inner), layout_(layout), corner_bytes_(corners.floats() * sizeof(float)),
        first_byte_(corners.first_offset(layout) * sizeof(float)), values_(std::move(values)) {}
  Result<std::span<std::byte>> reserve(std::size_t max_records) override {
    auto space = inner_.reserve(max_records);
    if (space.ok()) reserved_ = space.value();
    return space;
  }
  Status commit(std::size_t records) override {
    const std::size_t record_bytes = soup_record_bytes(layout_);
    for (std::size_t done = 0; done < records;) {
      auto block = values_.read(records - done);
      if (!block.ok()) return block.status();
      if (block->empty())
        return io_error("corner file '" + values_.path().string() + "' ended before the soup");
      const std::size_t n = block->size() / (3 * corner_bytes_);
      for (std::size_t i = 0; i < n; ++i, ++next_) {
        std::byte* record = reserved_.data() + (done + i) * record_bytes;
        if (load_soup_triangle_id(record, layout_) != TriangleId{next_})
          return io_error("corner file '" + values_.path().string() + "' is out of step with the soup at triangle " +
                          std::to_string(next_));
        for (int c = 0; c < 3; ++c)
          std::memcpy(record + soup_corner_offset(layout_, c) + first_byte_,
                      block->data() + (3 * i + static_cast<std::size_t>(c)) * corner_bytes_, corner_bytes_);
      }
      done += n;
    }
    return inner_.commit(records);
  }

  // Bytes per triangle of the corner file.
  static std::size_t triangle_bytes(CornerAttributes corners) { return 3 * corners.floats() * sizeof(float); }

 private:
  RecordOutput& inner_;
  VertexLayout layout_;
  std::size_t corner_bytes_;  // one corner's values
  std::size_t first_byte_;    // their offset within a corner of a record
  RecordReader values_;
  std::span<std::byte> reserved_;
  std::uint32_t next_ = 0;  // triangle id of the next record
};

class SoupBuilder {
 public:
  SoupBuilder(const SoupOptions& options, std::size_t io_bytes)
      : options_(options), io_(io_bytes) {}

  Result<SoupResult> run(const std::filesystem::path& ply) {
    const auto start = std::chrono::steady_clock::now();
    OCTOLOD_RETURN_IF_ERROR(open_reader(ply));
    const PlyInfo info = reader_->info();
    layout_ = info.layout;
    split_total_ = info.vertex_count + info.face_count;
    face_count_ = info.face_count;
    corners_ = info.corners;
    const std::uint64_t vertex_array_bytes = info.vertex_count * layout_.bytes();
    const bool in_core =
        !options_.force_out_of_core && vertex_array_bytes <= options_.memory_budget_bytes / 2;
    Status status;
    // an indexed mesh has one value per vertex: attributes per corner take the records path
    if (in_core && !corners_.any() && options_.mesh_sink.consume &&
        options_.mesh_sink.accepts(layout_, info.vertex_count, info.face_count)) {
      bool fanned_out = false;
      status = run_mesh(info.vertex_count, info.face_count, fanned_out);
      if (fanned_out) {  // more triangles than the mesh's arrays hold: the records path
        OCTOLOD_RETURN_IF_ERROR(open_reader(ply));
        status = run_in_core(info.vertex_count);
      } else {
        result_.mesh_consumed = true;
      }
    } else {
      status = in_core ? run_in_core(info.vertex_count) : run_out_of_core();
    }
    if (!status.ok()) return status;

    result_.soup = std::move(soup_file_);
    result_.layout = layout_;
    result_.in_core = in_core;
    result_.seconds.total = seconds_since(start) - consume_seconds_;
    for (const SortStats& s : result_.sorts) result_.seconds.sort += s.seconds;
    result_.seconds.split = split_wall_ - split_sort_seconds_ - window_in_split_seconds_;
    result_.seconds.dereference =
        std::max(0.0, result_.seconds.total - result_.seconds.split - result_.seconds.sort);
    return std::move(result_);
  }

 private:
  SortOptions sort_options(std::uint64_t budget) const {
    SortOptions o;
    o.memory_budget_bytes = budget;
    o.work_dir = options_.work_dir;
    o.threads = options_.threads;
    return o;
  }

  void progress(std::string_view stage, std::uint64_t done, std::uint64_t total) const {
    if (options_.progress) options_.progress(stage, std::min(done, total), total);
  }

  // The soup's output, opened once the stage's other buffers hold `bytes_in_use`; tells the
  // caller's sink_start what the stage leaves of the budget.
  Result<std::unique_ptr<SoupOutput>> open_output(bool in_core, std::uint64_t bytes_in_use) {
    if (options_.sink && options_.sink_start) {
      SoupSinkStart start;
      start.layout = layout_;
      start.bounds = result_.bounds;
      start.in_core = in_core;
      start.free_budget_bytes =
          options_.memory_budget_bytes - std::min(bytes_in_use, options_.memory_budget_bytes);
      OCTOLOD_RETURN_IF_ERROR(options_.sink_start(start));
    }
    return SoupOutput::open(options_, layout_, io_, soup_file_);
  }

  Status open_reader(const std::filesystem::path& ply) {
    PlyReadOptions read_options;
    read_options.buffer_bytes = io_;
    read_options.recentre_double_positions = options_.recentre_double_positions;
    auto reader = PlyReader::open(ply, read_options);
    if (!reader.ok()) return reader.status();
    reader_ = std::move(reader).value();
    return {};
  }

  // Runs the split into `sinks` and records the split's wall time and the sort time inside it
  // (`sorter`'s, if any).
  Status split(SplitSinks sinks, const RecordSorter* sorter) {
    const auto start = std::chrono::steady_clock::now();
    sinks.progress = [this](std::uint64_t done) { progress("split", done, split_total_); };
    std::optional<RecordWriter> corner_writer;
    if (corners_.any()) {
      corner_file_ = make_temp_file(options_.work_dir, "corners");
      const std::size_t triangle_bytes = CornerValuesOutput::triangle_bytes(corners_);
      auto writer = RecordWriter::create(corner_file_.path(), triangle_bytes, io_);
      if (!writer.ok()) return writer.status();
      corner_writer.emplace(std::move(writer).value());
      sinks.corner_values = [&, triangle_bytes](std::span<const float> values) {
        return corner_writer->append(reinterpret_cast<const std::byte*>(values.data()),
                                     values.size_bytes() / triangle_bytes);
      };
    }
    auto split = split_ply(*reader_, io_, sinks);
    if (!split.ok()) return split.status();
    if (corner_writer) OCTOLOD_RETURN_IF_ERROR(corner_writer->finish());
    reader_.reset();  // frees the PLY buffers before the next phase
    result_.vertex_count = split->vertex_count;
    result_.triangle_count = split->triangle_count;
    result_.bounds = split->bounds;
    result_.origin = split->origin;
    result_.input_trailing_bytes = split->trailing_bytes;
    split_wall_ = seconds_since(start);
    split_sort_seconds_ = sorter ? sorter->stats().seconds : 0.0;
    return {};
  }

  // Vertices and triangles in memory, handed to SoupOptions::mesh_sink. Sets `fanned_out`
  // (and returns an error) when the faces give more than `face_count` triangles.
  Status run_mesh(std::uint64_t vertex_count, std::uint64_t face_count, bool& fanned_out) {
    const std::size_t floats = layout_.floats();
    PageArray<float> vertices(vertex_count * floats);
    PageArray<std::uint32_t> triangles(3 * face_count);
    std::uint64_t triangle_count = 0;
    SplitSinks sinks;
    sinks.vertices = [&](std::uint64_t first, std::span<const float> v) {
      std::copy(v.begin(), v.end(), vertices.get() + first * floats);
      return Status{};
    };
    sinks.triangles = [&](std::span<const TriangleRecord> t) {
      if (triangle_count + t.size() > face_count) {
        fanned_out = true;
        return unsupported_error("polygons fan out into more triangles than the faces declared");
      }
      std::uint32_t* out = triangles.get() + 3 * triangle_count;
      for (const TriangleRecord& r : t) {
        for (int c = 0; c < 3; ++c) *out++ = static_cast<std::uint32_t>(r.corner[c]);
      }
      triangle_count += t.size();
      return Status{};
    };
    OCTOLOD_RETURN_IF_ERROR(split(std::move(sinks), nullptr));
    SoupMesh mesh;
    mesh.layout = layout_;
    mesh.vertices = std::span<const float>(vertices.get(), vertex_count * floats);
    mesh.triangles = std::span<const std::uint32_t>(triangles.get(), 3 * triangle_count);
    mesh.bounds = result_.bounds;
    const std::uint64_t in_use = vertex_count * layout_.bytes() + 12 * face_count;
    mesh.free_budget_bytes =
        options_.memory_budget_bytes - std::min(in_use, options_.memory_budget_bytes);
    const auto start = std::chrono::steady_clock::now();
    Status consumed = options_.mesh_sink.consume(mesh);
    consume_seconds_ = seconds_since(start);
    return consumed;
  }

  // Vertices in memory; triangle records sorted into the output order, then gathered.
  Status run_in_core(std::uint64_t vertex_count) {
    const std::size_t floats = layout_.floats();
    const std::uint64_t vertex_array_bytes = vertex_count * layout_.bytes();
    PageArray<float> vertices(vertex_count * floats);
    // Budget: the vertex array and the sort throughout, plus the PLY reader and the triangle
    // batch while splitting, then the output batch and the soup writer. The array is at most
    // half the budget, so the sort gets at least 1/4 of it minus the reader's file buffer.
    const std::uint64_t sort_budget =
        options_.memory_budget_bytes - vertex_array_bytes - (corners_.any() ? 3 : 2) * io_ - kPlyFileBuffer;
    // Triangle order for either SoupOrder: the split's order already, so the sort only holds
    // the records (spilling runs when they do not fit) until the vertex array is complete.
    auto sorter = RecordSorter::create(
        sizeof(TriangleRecord),
        sort_key_u32_at(offsetof(TriangleRecord, triangle), sizeof(TriangleRecord)),
        sort_options(sort_budget));
    if (!sorter.ok()) return sorter.status();
    RecordSorter& triangles = *sorter.value();

    SplitSinks sinks;
    sinks.vertices = [&](std::uint64_t first, std::span<const float> v) {
      std::copy(v.begin(), v.end(), vertices.get() + first * floats);
      return Status{};
    };
    sinks.triangles = [&](std::span<const TriangleRecord> t) {
      return triangles.push(std::as_bytes(t));
    };
    OCTOLOD_RETURN_IF_ERROR(split(std::move(sinks), &triangles));
    OCTOLOD_RETURN_IF_ERROR(triangles.finish());
    progress("dereference", 0, result_.triangle_count);

    // In use while the soup is written: the vertex array, the sort, the output batch (and the
    // corner file's reader).
    auto soup = open_output(true, vertex_array_bytes + sort_budget + (corners_.any() ? 2 : 1) * io_);
    if (!soup.ok()) return soup.status();
    auto last = with_corner_values(*soup.value());
    if (!last.ok()) return last.status();
    ProgressOutput out(*last.value(), [this](std::uint64_t done) {
      progress("dereference", done, result_.triangle_count);
    });
    OCTOLOD_RETURN_IF_ERROR(dereference_in_core(
        layout_, std::span<const float>(vertices.get(), vertex_count * floats), triangles, out));
    OCTOLOD_RETURN_IF_ERROR(soup.value()->finish());
    result_.sorts.push_back(triangles.stats());
    return {};
  }

  // Out of core: the split writes the vertex file and hands the triangles to the window pass
  // (dereference.h), which dereferences those whose corners lie close together in the vertex
  // file; the seed's three sorted passes take the rest.
  Status run_out_of_core() {
    // Budget: the window pass holds the window and the far triangles' sort (forming runs), the
    // passes two sorts (one merging, one forming runs); the window and each sort get a quarter
    // of what six io buffers and the PLY reader's file buffer leave. The window pass runs
    // inside the split, with the PLY reader, the triangle batch, the vertex reader and the
    // output batch; the other half of the budget is the soup's consumer's
    // (SoupOptions::sink_start), or the order sort's for SoupOrder::by_triangle, which
    // attributes per corner take too (they are patched into the records in triangle order, read through one more
    // io buffer, which the split wrote through another).
    const bool by_triangle = options_.order == SoupOrder::by_triangle || corners_.any();
    const std::uint64_t quarter =
        (options_.memory_budget_bytes - (corners_.any() ? 7 : 6) * io_ - kPlyFileBuffer) / 4;
    TempFile vertex_file = make_temp_file(options_.work_dir, "vertices");
    TempFile triangle_file;  // only when faces come before the last vertex
    std::optional<RecordWriter> vertex_writer;
    std::optional<RecordWriter> triangle_writer;
    // The soup records' way out: the soup output, or the order sort in front of it.
    std::unique_ptr<SoupOutput> soup;
    std::unique_ptr<RecordSorter> order;
    std::unique_ptr<RecordOutput> order_input;
    RecordOutput* records = nullptr;
    // The window pass, and the far triangles' sort by corner 0's vertex id.
    std::optional<RecordReader> window_vertices;
    std::unique_ptr<ProgressOutput> window_out;
    std::unique_ptr<WindowDereferencer> window;
    std::unique_ptr<RecordSorter> far;

    // Once the vertex file is complete: the outputs and the window.
    auto start_window = [&]() -> Status {
      OCTOLOD_RETURN_IF_ERROR(vertex_writer->finish());
      vertex_writer.reset();
      if (by_triangle) {
        auto created = RecordSorter::create(
            soup_record_bytes(layout_),
            sort_key_u32_at(soup_triangle_id_offset(layout_), soup_record_bytes(layout_)),
            sort_options(quarter));
        if (!created.ok()) return created.status();
        order = std::move(created).value();
        order_input = std::make_unique<SorterOutput>(*order);
        records = order_input.get();
      } else {
        // In use: the window, the far sort, the PLY reader, four io buffers.
        auto opened = open_output(false, 2 * quarter + 5 * io_ + kPlyFileBuffer);
        if (!opened.ok()) return opened.status();
        soup = std::move(opened).value();
        records = soup.get();
      }
      auto reader = RecordReader::open(vertex_file.path(), layout_.bytes(), io_);
      if (!reader.ok()) return reader.status();
      window_vertices.emplace(std::move(reader).value());
      window_out = std::make_unique<ProgressOutput>(*records, [this](std::uint64_t done) {
        progress("dereference", done, face_count_);
      });
      window = std::make_unique<WindowDereferencer>(
          layout_, std::bit_floor(std::max<std::uint64_t>(quarter / layout_.bytes(), 1)),
          *window_vertices, *window_out, [&](std::span<const TriangleRecord> t) -> Status {
            if (!far) {
              auto created = RecordSorter::create(
                  sizeof(TriangleRecord), sort_key_u32_at(working_vertex_id_offset(layout_, 0), 16),
                  sort_options(quarter));
              if (!created.ok()) return created.status();
              far = std::move(created).value();
            }
            return far->push(std::as_bytes(t));
          });
      return {};
    };

    auto created = RecordWriter::create(vertex_file.path(), layout_.bytes(), io_);
    if (!created.ok()) return created.status();
    vertex_writer.emplace(std::move(created).value());
    SplitSinks sinks;
    sinks.vertices = [&](std::uint64_t, std::span<const float> v) {
      return vertex_writer->append(reinterpret_cast<const std::byte*>(v.data()),
                                   v.size() / layout_.floats());
    };
    // The usual order, every vertex before the faces: the window pass runs as faces are read.
    sinks.vertices_done = [&](const Bounds& bounds) {
      result_.bounds = bounds;
      return start_window();
    };
    sinks.triangles = [&](std::span<const TriangleRecord> t) -> Status {
      if (window) {  // timed apart: the pass is dereferencing, not splitting
        const auto start = std::chrono::steady_clock::now();
        Status added = window->add(t);
        window_in_split_seconds_ += seconds_since(start);
        return added;
      }
      if (!triangle_writer) {
        triangle_file = make_temp_file(options_.work_dir, "triangles");
        auto writer = RecordWriter::create(triangle_file.path(), sizeof(TriangleRecord), io_);
        if (!writer.ok()) return writer.status();
        triangle_writer.emplace(std::move(writer).value());
      }
      return triangle_writer->append(reinterpret_cast<const std::byte*>(t.data()), t.size());
    };
    OCTOLOD_RETURN_IF_ERROR(split(std::move(sinks), nullptr));
    if (!window) {  // faces before the last vertex (the seed's triangle file), or none
      if (triangle_writer) OCTOLOD_RETURN_IF_ERROR(triangle_writer->finish());
      OCTOLOD_RETURN_IF_ERROR(start_window());
      if (triangle_writer) {
        triangle_writer.reset();
        auto triangles = RecordReader::open(triangle_file.path(), sizeof(TriangleRecord), io_);
        if (!triangles.ok()) return triangles.status();
        for (;;) {
          auto block = triangles->read();
          if (!block.ok()) return block.status();
          if (block->empty()) break;
          OCTOLOD_RETURN_IF_ERROR(window->add(std::span<const TriangleRecord>(
              reinterpret_cast<const TriangleRecord*>(block->data()),
              block->size() / sizeof(TriangleRecord))));
        }
      }
    }
    OCTOLOD_RETURN_IF_ERROR(window->finish());
    result_.far_triangles = window->stats().far;
    window.reset();
    window_out.reset();
    window_vertices.reset();
    triangle_file.remove();
    if (far) {
      OCTOLOD_RETURN_IF_ERROR(far->finish());
      OCTOLOD_RETURN_IF_ERROR(run_passes(std::move(far), quarter, vertex_file.path(), *records));
    }
    vertex_file.remove();
    if (order) {
      OCTOLOD_RETURN_IF_ERROR(order->finish());
      // In use: the merging order sort, the output batch (and the corner file's reader).
      auto opened = open_output(false, quarter + (corners_.any() ? 2 : 1) * io_);
      if (!opened.ok()) return opened.status();
      soup = std::move(opened).value();
      auto last = with_corner_values(*soup);
      if (!last.ok()) return last.status();
      OCTOLOD_RETURN_IF_ERROR(drain_order(*order, *last.value()));
    }
    return soup->finish();
  }

  // The seed's three passes over `current` (finished, sorted by corner 0's vertex id), each
  // sorted stream feeding the next pass's sort; the last pass's records go to `last`.
  Status run_passes(std::unique_ptr<RecordSorter> current, std::uint64_t sort_budget,
                    const std::filesystem::path& vertex_file, RecordOutput& last) {
    const std::uint64_t total = current->stats().records;
    static constexpr const char* kPassNames[3] = {"dereference 0", "dereference 1",
                                                  "dereference 2"};
    for (int corner = 0; corner < 3; ++corner) {
      const int filled = corner + 1;
      std::unique_ptr<RecordSorter> next;
      std::unique_ptr<RecordOutput> sorter_output;
      if (filled < 3) {
        const std::size_t out_bytes = working_record_bytes(layout_, filled);
        auto created = RecordSorter::create(
            out_bytes, sort_key_u32_at(working_vertex_id_offset(layout_, filled), out_bytes),
            sort_options(sort_budget));
        if (!created.ok()) return created.status();
        next = std::move(created).value();
        sorter_output = std::make_unique<SorterOutput>(*next);
      }
      const char* stage = kPassNames[corner];
      ProgressOutput out(next ? *sorter_output : last, [this, stage, total](std::uint64_t done) {
        progress(stage, done, total);
      });
      auto vertices = RecordReader::open(vertex_file, layout_.bytes(), io_);
      if (!vertices.ok()) return vertices.status();
      OCTOLOD_RETURN_IF_ERROR(dereference_pass(corner, layout_, *current, vertices.value(), out));
      result_.sorts.push_back(current->stats());
      current.reset();  // frees its buffers before the next sort merges
      if (!next) break;
      OCTOLOD_RETURN_IF_ERROR(next->finish());
      current = std::move(next);
    }
    return {};
  }

  // The records' way into `soup` once they come in triangle order: through a
  // CornerValuesOutput when the faces give their corners attributes (kept as corner_output_),
  // else straight.
  Result<RecordOutput*> with_corner_values(RecordOutput& soup) {
    if (!corners_.any()) return &soup;
    auto values = RecordReader::open(corner_file_.path(), CornerValuesOutput::triangle_bytes(corners_), io_);
    if (!values.ok()) return values.status();
    corner_output_ = std::make_unique<CornerValuesOutput>(soup, layout_, corners_, std::move(values).value());
    return corner_output_.get();
  }

  // SoupOrder::by_triangle: the order sort's stream written to the soup.
  Status drain_order(RecordSorter& order, RecordOutput& soup) {
    const std::size_t record_bytes = soup_record_bytes(layout_);
    std::uint64_t done = 0;
    for (;;) {
      auto block = order.next();
      if (!block.ok()) return block.status();
      if (block->empty()) break;
      // Through reserve/commit, so a sink sees batches of at most its batch size.
      const std::byte* src = block->data();
      std::size_t left = block->size() / record_bytes;
      while (left > 0) {
        auto space = soup.reserve(left);
        if (!space.ok()) return space.status();
        std::memcpy(space->data(), src, space->size());
        const std::size_t n = space->size() / record_bytes;
        OCTOLOD_RETURN_IF_ERROR(soup.commit(n));
        src += space->size();
        left -= n;
      }
      done += block->size() / record_bytes;
      progress("order", done, result_.triangle_count);
    }
    result_.sorts.push_back(order.stats());
    return {};
  }

  const SoupOptions& options_;
  const std::size_t io_;  // one file buffer / batch: budget / 16 within [4 KiB, 1 MiB]
  std::unique_ptr<PlyReader> reader_;
  VertexLayout layout_;
  std::uint64_t split_total_ = 0;
  std::uint64_t face_count_ = 0;  // declared: the progress total while triangles are counted
  double split_wall_ = 0;
  double split_sort_seconds_ = 0;
  double consume_seconds_ = 0;  // inside SoupOptions::mesh_sink.consume
  double window_in_split_seconds_ = 0;  // the window pass run from the split's triangle sink
  TempFile soup_file_;
  CornerAttributes corners_;     // what the faces give their corners (PlyInfo)
  TempFile corner_file_;         // the split wrote their values here, in triangle order
  std::unique_ptr<CornerValuesOutput> corner_output_;
  SoupResult result_;
};

}  // namespace

Result<SoupResult> build_soup(const std::filesystem::path& ply, const SoupOptions& options) {
  if (options.memory_budget_bytes < kMinSoupBudget) {
    return usage_error("soup memory budget of " + std::to_string(options.memory_budget_bytes) +
                       " bytes is below the minimum of " + std::to_string(kMinSoupBudget));
  }
  std::error_code ec;
  if (!options.work_dir.empty() && !std::filesystem::is_directory(options.work_dir, ec)) {
    return usage_error("work directory '" + options.work_dir.string() + "' does not exist or is not a directory");
  }
  const std::size_t io = std::clamp<std::size_t>(
      static_cast<std::size_t>(std::min<std::uint64_t>(options.memory_budget_bytes / 16,
                                                       std::size_t{1} << 20)),
      4096, std::size_t{1} << 20);
  SoupBuilder builder(options, io);
  return builder.run(ply);
}

}  // namespace octolod::bake
