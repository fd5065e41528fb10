// Streaming PLY writer (seed 4.2.1's vertex and triangle files, written as PLY for interchange):
// the header from ply.cpp's format_header, vertices and triangles encoded into a 64 KiB buffer
// and written with write(2), so ENOSPC and friends surface as io errors naming the file. The
// file is written to a "<path>.tmp-<random>" sibling and renamed over `path` by finish().
#include "octolod/formats/ply_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "octolod/formats/output_file.h"
#include "octolod/formats/unique_fd.h"
#include "ply_header.h"

namespace octolod {
namespace {

constexpr std::size_t kBufferBytes = std::size_t{64} << 10;
// Room one encoded vertex or triangle needs at most (ascii: 14 values of <= 33 characters).
constexpr std::size_t kMaxRecordBytes = 512;

ply::Header header_for(const PlyWriteOptions& options, std::uint64_t vertex_count,
                       std::uint64_t triangle_count) {
  using ply::ScalarType;
  ply::Header header;
  header.format = options.format;
  header.comments = options.comments;
  ply::Element vertex{"vertex", vertex_count, {}, 0};
  auto add = [&](const char* name, ScalarType type) {
    vertex.properties.push_back(ply::Property{name, type, false, ScalarType::uint8});
  };
  for (const char* name : {"x", "y", "z"})
    add(name, options.position_origin ? ScalarType::float64 : ScalarType::float32);
  if (options.layout.normal)
    for (const char* name : {"nx", "ny", "nz"}) add(name, ScalarType::float32);
  if (options.layout.color) {
    const ScalarType type =
        options.color_type == PlyColorType::uchar ? ScalarType::uint8 : ScalarType::float32;
    for (const char* name : {"red", "green", "blue"}) add(name, type);
  }
  if (options.layout.uv)
    for (const char* name : {"u", "v"}) add(name, ScalarType::float32);
  // `int` as every tool expects, unless the indices need the 32nd bit.
  const ScalarType index_type = vertex_count <= (std::uint64_t{1} << 31) ? ScalarType::int32
                                                                         : ScalarType::uint32;
  ply::Element face{"face", triangle_count, {}, 0};
  face.properties.push_back(ply::Property{"vertex_indices", index_type, true, ScalarType::uint8});
  header.elements = {std::move(vertex), std::move(face)};
  return header;
}

std::uint8_t color_byte(float c) {
  if (!(c > 0.0f)) return 0;  // also NaN
  if (c >= 1.0f) return 255;
  return static_cast<std::uint8_t>(std::lround(c * 255.0f));
}

class FileWriter final : public PlyWriter {
 public:
  FileWriter(std::filesystem::path path, std::string temp, UniqueFd fd, const PlyWriteOptions& options,
             std::uint64_t vertex_count, std::uint64_t triangle_count)
      : path_(std::move(path)), temp_(std::move(temp)), fd_(std::move(fd)), format_(options.format),
        layout_(options.layout), color_type_(options.color_type), origin_(options.position_origin),
        vertex_count_(vertex_count),
        triangle_count_(triangle_count),
        swap_(options.format != PlyFormat::ascii && !ply::native_format_is(options.format)) {
  }

  ~FileWriter() override {
    if (!finished_) ::unlink(temp_.c_str());
  }

  Status start(const std::string& header) {
    for (std::size_t done = 0; done < header.size();) {
      const std::size_t n = std::min(header.size() - done, kBufferBytes - used_);
      std::memcpy(buffer_.get() + used_, header.data() + done, n);
      used_ += n;
      done += n;
      OCTOLOD_RETURN_IF_ERROR(flush_if_full());
    }
    return {};
  }

  Status write_vertices(std::span<const float> vertices) override {
    OCTOLOD_RETURN_IF_ERROR(check_usable());
    const std::size_t floats = layout_.floats();
    if (vertices.size() % floats != 0)
      return misuse("write_vertices got " + std::to_string(vertices.size()) +
                    " floats, not a multiple of " + std::to_string(floats) + " per vertex");
    const std::uint64_t count = vertices.size() / floats;
    if (count > vertex_count_ - vertices_written_)
      return misuse("more vertices than the declared " + std::to_string(vertex_count_));
    for (std::size_t i = 0; i < count; ++i) {
      encode_vertex(vertices.data() + i * floats);
      OCTOLOD_RETURN_IF_ERROR(flush_if_full());
    }
    vertices_written_ += count;
    return {};
  }

  Status write_triangles(std::span<const std::uint32_t> triangles) override {
    OCTOLOD_RETURN_IF_ERROR(check_usable());
    if (vertices_written_ != vertex_count_)
      return misuse("triangles written before all " + std::to_string(vertex_count_) +
                    " vertices (" + std::to_string(vertices_written_) + " so far)");
    if (triangles.size() % 3 != 0)
      return misuse("write_triangles got " + std::to_string(triangles.size()) +
                    " indices, not a multiple of 3");
    const std::uint64_t count = triangles.size() / 3;
    if (count > triangle_count_ - triangles_written_)
      return misuse("more triangles than the declared " + std::to_string(triangle_count_));
    for (const std::uint32_t index : triangles)
      if (index >= vertex_count_)
        return misuse("vertex index " + std::to_string(index) + " out of range (" +
                      std::to_string(vertex_count_) + " vertices)");
    for (std::size_t i = 0; i < count; ++i) {
      encode_triangle(triangles.data() + i * 3);
      OCTOLOD_RETURN_IF_ERROR(flush_if_full());
    }
    triangles_written_ += count;
    return {};
  }

  Status finish() override {
    OCTOLOD_RETURN_IF_ERROR(check_usable());
    if (vertices_written_ != vertex_count_ || triangles_written_ != triangle_count_)
      return misuse("finish() after " + std::to_string(vertices_written_) + " of " +
                    std::to_string(vertex_count_) + " vertices and " +
                    std::to_string(triangles_written_) + " of " + std::to_string(triangle_count_) +
                    " triangles");
    OCTOLOD_RETURN_IF_ERROR(flush());
    if (::close(fd_.release()) != 0) return fail("close failed");
    if (std::rename(temp_.c_str(), path_.c_str()) != 0) return fail("rename from " + temp_ + " failed");
    finished_ = true;
    return {};
  }

 private:
  Status check_usable() const {
    if (finished_) return usage_error(path_.string() + ": PlyWriter used after finish()");
    if (!failure_.ok()) return failure_;
    return {};
  }
  Status misuse(const std::string& what) {
    failure_ = usage_error(path_.string() + ": " + what);
    return failure_;
  }
  Status fail(const std::string& what) {
    failure_ = io_error(path_.string() + ": " + what + ": " + std::strerror(errno));
    return failure_;
  }

  // Appends to the buffer; flush_if_full() after each record keeps kMaxRecordBytes free.
  void put(const char* bytes, std::size_t n) {
    std::memcpy(buffer_.get() + used_, bytes, n);
    used_ += n;
  }

  template <class T>
  void put_binary(T value) {
    static_assert(sizeof(T) == 8 || sizeof(T) == 4 || sizeof(T) == 1);
    if constexpr (sizeof(T) == 8) {
      std::uint64_t bits = std::bit_cast<std::uint64_t>(value);
      if (swap_) bits = ply::byte_swap(bits);
      put(reinterpret_cast<const char*>(&bits), 8);
    } else if constexpr (sizeof(T) == 4) {
      std::uint32_t bits = std::bit_cast<std::uint32_t>(value);
      if (swap_) bits = ply::byte_swap(bits);
      put(reinterpret_cast<const char*>(&bits), 4);
    } else {
      buffer_[used_++] = static_cast<char>(value);
    }
  }

  template <class T>
  void put_text(T value, char separator) {
    char* out = buffer_.get() + used_;
    const auto [end, ec] = std::to_chars(out, out + 32, value);
    (void)ec;  // 32 characters hold any double or 32-bit integer
    *end = separator;
    used_ = static_cast<std::size_t>(end + 1 - buffer_.get());
  }

  void encode_vertex(const float* v) {
    const std::uint32_t floats = layout_.floats();
    const bool byte_color = layout_.color && color_type_ == PlyColorType::uchar;
    const std::uint32_t color_begin = layout_.color_offset();
    for (std::uint32_t i = 0; i < floats; ++i) {
      const bool is_color = layout_.color && i >= color_begin && i < color_begin + 3;
      const char separator = i + 1 == floats ? '\n' : ' ';
      if (origin_ && i < 3) {
        const double absolute = static_cast<double>(v[i]) + (*origin_)[i];
        if (format_ == PlyFormat::ascii) put_text(absolute, separator);
        else put_binary(absolute);
      } else if (format_ == PlyFormat::ascii) {
        if (is_color && byte_color)
          put_text(static_cast<unsigned>(color_byte(v[i])), separator);
        else
          put_text(v[i], separator);
      } else if (is_color && byte_color) {
        put_binary(color_byte(v[i]));
      } else {
        put_binary(v[i]);
      }
    }
  }

  void encode_triangle(const std::uint32_t* t) {
    if (format_ == PlyFormat::ascii) {
      put("3 ", 2);
      put_text(t[0], ' ');
      put_text(t[1], ' ');
      put_text(t[2], '\n');
    } else {
      put_binary(std::uint8_t{3});
      for (int k = 0; k < 3; ++k) put_binary(t[k]);
    }
  }

  Status flush_if_full() { return used_ + kMaxRecordBytes > kBufferBytes ? flush() : Status{}; }

  Status flush() {
    std::size_t done = 0;
    while (done < used_) {
      const ssize_t n = ::write(fd_.get(), buffer_.get() + done, used_ - done);
      if (n < 0) {
        if (errno == EINTR) continue;
        return fail("write failed");
      }
      done += static_cast<std::size_t>(n);
    }
    used_ = 0;
    return {};
  }

  std::filesystem::path path_;
  std::string temp_;
  UniqueFd fd_;
  PlyFormat format_;
  VertexLayout layout_;
  PlyColorType color_type_;
  std::optional<std::array<double, 3>> origin_;  // positions written as double, plus it
  std::uint64_t vertex_count_;
  std::uint64_t triangle_count_;
  bool swap_;
  std::unique_ptr<char[]> buffer_ = std::make_unique<char[]>(kBufferBytes);
  std::size_t used_ = 0;
  std::uint64_t vertices_written_ = 0;
  std::uint64_t triangles_written_ = 0;
  bool finished_ = false;
  Status failure_;
};

// Creates "<path>.tmp-<16 hex digits>" exclusively, mode 0666 minus the umask like any new file.
Result<std::pair<std::string, UniqueFd>> create_temporary(const std::filesystem::path& path) {
  static thread_local std::mt19937_64 random{std::random_device{}() ^
                                              static_cast<std::uint64_t>(::getpid())};
  for (int attempt = 0; attempt < 100; ++attempt) {
    char suffix[24];
    std::snprintf(suffix, sizeof(suffix), ".tmp-%016llx",
                  static_cast<unsigned long long>(random()));
    std::string temp = path.string() + suffix;
    UniqueFd fd(::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666));
    if (fd.valid()) return std::pair{std::move(temp), std::move(fd)};
    if (errno != EEXIST)
      return io_error(path.string() + ": cannot create temporary file " + temp + ": " +
                      std::strerror(errno));
  }
  return io_error(path.string() + ": cannot create a unique temporary file");
}

}  // namespace

Result<std::unique_ptr<PlyWriter>> PlyWriter::create(const std::filesystem::path& path,
                                                     const PlyWriteOptions& options,
                                                     std::uint64_t vertex_count,
                                                     std::uint64_t triangle_count) {
  for (const std::string& comment : options.comments)
    if (comment.find_first_of("\r\n") != std::string::npos)
      return usage_error(path.string() + ": PLY comment contains a line break: " + comment);
  OCTOLOD_RETURN_IF_ERROR(check_output_file(path, "the PLY"));
  Result<std::pair<std::string, UniqueFd>> temp = create_temporary(path);
  if (!temp.ok()) return temp.status();
  auto writer = std::make_unique<FileWriter>(path, temp->first, std::move(temp->second), options,
                                             vertex_count, triangle_count);
  OCTOLOD_RETURN_IF_ERROR(writer->start(ply::format_header(header_for(options, vertex_count,
                                                                      triangle_count))));
  return std::unique_ptr<PlyWriter>(std::move(writer));
}

Status write_ply(const std::filesystem::path& path, const PlyWriteOptions& options,
                 std::span<const float> vertices, std::span<const std::uint32_t> triangles) {
  const std::size_t floats = options.layout.floats();
  if (vertices.size() % floats != 0 || triangles.size() % 3 != 0)
    return usage_error(path.string() + ": write_ply got " + std::to_string(vertices.size()) +
                       " floats and " + std::to_string(triangles.size()) +
                       " indices: not whole vertices and triangles");
  Result<std::unique_ptr<PlyWriter>> writer =
      PlyWriter::create(path, options, vertices.size() / floats, triangles.size() / 3);
  if (!writer.ok()) return writer.status();
  OCTOLOD_RETURN_IF_ERROR(writer.value()->write_vertices(vertices));
  OCTOLOD_RETURN_IF_ERROR(writer.value()->write_triangles(triangles));
  return writer.value()->finish();
}

}  // namespace octolod
