// Node LOD file encoding/decoding; the layout is documented in node_file.h and docs/formats.md.
#include "octolod/formats/node_file.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "byte_io.h"
#include "octolod/formats/unique_fd.h"

namespace octolod {
namespace {

constexpr std::array<char, 8> kMagic{'O', 'C', 'T', 'O', 'L', 'O', 'D', '\0'};
constexpr std::size_t kCrcBytes = 4;

std::uint32_t index_bytes_for(std::size_t vertex_count) { return vertex_count <= 0xFFFFu ? 2u : 4u; }

Status corrupt(std::string_view name, std::size_t offset, const std::string& what) {
  return bad_input_error(std::string(name) + ": byte offset " + std::to_string(offset) + ": " + what);
}

}  // namespace

std::uint32_t crc32(std::span<const std::byte> bytes, std::uint32_t crc) {
  // zlib's table-driven CRC processes several bytes per step: a byte-wise loop took ~15% of a
  // --method none bake's cycles.
  return static_cast<std::uint32_t>(
      ::crc32_z(crc, reinterpret_cast<const Bytef*>(bytes.data()), bytes.size()));
}

Bounds NodeMesh::bounds() const {
  Bounds b;
  const std::size_t stride = layout.floats();
  for (std::size_t i = 0; i + stride <= vertices.size(); i += stride) b.extend(&vertices[i]);
  return b;
}

std::size_t node_file_size(const NodeMesh& mesh) {
  return kNodeFileHeaderBytes + mesh.vertices.size() * sizeof(float) +
         mesh.indices.size() * index_bytes_for(mesh.vertex_count()) + kCrcBytes;
}

namespace {

void append_header(std::vector<std::byte>& out, VertexLayout layout, std::uint32_t vertex_count,
                   std::uint32_t index_count, const Bounds& bounds) {
  for (char c : kMagic) out.push_back(static_cast<std::byte>(c));
  detail::append_le(out, kNodeFileVersion);
  detail::append_le(out, layout.mask());
  detail::append_le(out, vertex_count);
  detail::append_le(out, index_count);
  detail::append_le(out, index_bytes_for(vertex_count));
  detail::append_le(out, std::uint32_t{0});
  const Bounds b = vertex_count ? bounds : Bounds{{0, 0, 0}, {0, 0, 0}};
  for (float v : b.min) detail::append_le(out, v);
  for (float v : b.max) detail::append_le(out, v);
}

void append_index_bytes(std::vector<std::byte>& out, std::span<const std::uint32_t> indices,
                    std::uint32_t index_bytes) {
  for (std::uint32_t i : indices) {
    if (index_bytes == 2) detail::append_le(out, static_cast<std::uint16_t>(i));
    else detail::append_le(out, i);
  }
}

}  // namespace

std::vector<std::byte> encode_node_file(const NodeMesh& mesh) {
  assert(mesh.vertices.size() % mesh.layout.floats() == 0 && "NodeMesh: partial vertex");
  assert(mesh.indices.size() % 3 == 0 && "NodeMesh: partial triangle");
  std::vector<std::byte> out;
  out.reserve(node_file_size(mesh));
  append_header(out, mesh.layout, static_cast<std::uint32_t>(mesh.vertex_count()),
                static_cast<std::uint32_t>(mesh.indices.size()), mesh.bounds());
  const auto* vbytes = reinterpret_cast<const std::byte*>(mesh.vertices.data());
  out.insert(out.end(), vbytes, vbytes + mesh.vertices.size() * sizeof(float));
  for ([[maybe_unused]] std::uint32_t i : mesh.indices)
    assert(i < mesh.vertex_count() && "NodeMesh: index out of range");
  append_index_bytes(out, mesh.indices, index_bytes_for(mesh.vertex_count()));
  detail::append_le(out, crc32(out));
  return out;
}

Result<NodeMesh> decode_node_file(std::span<const std::byte> bytes, std::string_view name) {
  if (bytes.size() < kNodeFileHeaderBytes + kCrcBytes)
    return corrupt(name, bytes.size(), "truncated node file (" + std::to_string(bytes.size()) +
                                           " bytes, header needs " +
                                           std::to_string(kNodeFileHeaderBytes + kCrcBytes) + ")");
  for (std::size_t i = 0; i < kMagic.size(); ++i)
    if (bytes[i] != static_cast<std::byte>(kMagic[i])) return corrupt(name, i, "not an octolod node file (bad magic)");
  const auto version = detail::load_le<std::uint32_t>(bytes, 8);
  if (version != kNodeFileVersion)
    return Status(ErrorCode::unsupported, std::string(name) + ": byte offset 8: node file version " +
                                              std::to_string(version) + ", this build reads " +
                                              std::to_string(kNodeFileVersion));
  const auto mask = detail::load_le<std::uint32_t>(bytes, 12);
  if ((mask & ~VertexLayout::kValidMask) != 0) return corrupt(name, 12, "unknown attribute bits in layout mask");
  const auto vertex_count = detail::load_le<std::uint32_t>(bytes, 16);
  const auto index_count = detail::load_le<std::uint32_t>(bytes, 20);
  const auto index_bytes = detail::load_le<std::uint32_t>(bytes, 24);
  if (index_count % 3 != 0) return corrupt(name, 20, "index count not a multiple of 3");
  if (const auto reserved = detail::load_le<std::uint32_t>(bytes, 28); reserved != 0)
    return corrupt(name, 28, "reserved field is " + std::to_string(reserved) + ", not 0");
  if (index_bytes != index_bytes_for(vertex_count))
    return corrupt(name, 24, "index size " + std::to_string(index_bytes) + " does not match vertex count");
  NodeMesh mesh;
  mesh.layout = VertexLayout::from_mask(mask);
  // Sizes in 64-bit arithmetic: the counts are untrusted until they match the byte length.
  const std::uint64_t vertex_floats = std::uint64_t{vertex_count} * mesh.layout.floats();
  const std::uint64_t expected = kNodeFileHeaderBytes + vertex_floats * 4 +
                                 std::uint64_t{index_count} * index_bytes + kCrcBytes;
  if (expected != bytes.size())
    return corrupt(name, bytes.size() < expected ? bytes.size() : expected,
                   "size mismatch: header describes " + std::to_string(expected) + " bytes, file has " +
                       std::to_string(bytes.size()));
  const std::size_t crc_offset = bytes.size() - kCrcBytes;
  if (crc32(bytes.first(crc_offset)) != detail::load_le<std::uint32_t>(bytes, crc_offset))
    return corrupt(name, crc_offset, "checksum mismatch (file corrupted)");
  mesh.vertices.resize(static_cast<std::size_t>(vertex_floats));
  if (!mesh.vertices.empty())  // (an empty vector's data() may be null, which memcpy must not get)
    std::memcpy(mesh.vertices.data(), bytes.data() + kNodeFileHeaderBytes, mesh.vertices.size() * 4);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (!std::isfinite(mesh.vertices[i]))
      return corrupt(name, kNodeFileHeaderBytes + i * 4, "non-finite vertex value");
  // the header's bounds hold every position (readers may cull or quantize by them unread)
  const std::size_t stride = mesh.layout.floats();
  for (std::size_t k = 0; k < 3; ++k) {
    const float low = detail::load_le<float>(bytes, 32 + 4 * k), high = detail::load_le<float>(bytes, 44 + 4 * k);
    for (std::size_t v = 0; v < vertex_count; ++v) {
      const float c = mesh.vertices[v * stride + k];
      if (!(c >= low && c <= high))
        return corrupt(name, kNodeFileHeaderBytes + (v * stride + k) * 4,
                       "vertex " + std::to_string(v) + " lies outside the header's bounds");
    }
  }
  mesh.indices.resize(index_count);
  const std::size_t index_offset = kNodeFileHeaderBytes + mesh.vertices.size() * 4;
  for (std::size_t i = 0; i < index_count; ++i) {
    const std::size_t at = index_offset + i * index_bytes;
    std::uint32_t v = index_bytes == 2 ? detail::load_le<std::uint16_t>(bytes, at)
                                       : detail::load_le<std::uint32_t>(bytes, at);
    if (v >= vertex_count)
      return corrupt(name, at, "index " + std::to_string(v) + " >= vertex count " + std::to_string(vertex_count));
    mesh.indices[i] = v;
  }
  return mesh;
}

namespace {

// write(2) of all of `bytes`, again after EINTR: 0, or the errno of the failure (EIO for a write
// that wrote nothing).
int write_all(int fd, std::span<const std::byte> bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n < 0 ? errno : EIO;
    done += static_cast<std::size_t>(n);
  }
  return 0;
}

}  // namespace

Status write_node_file(const std::filesystem::path& path, const NodeMesh& mesh) {
  // One write(2) of the encoded bytes (no stdio buffer, whose setup costs an fstat per file: a
  // bake writes thousands of small files).
  const std::vector<std::byte> bytes = encode_node_file(mesh);
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return io_error(path.string() + ": cannot create: " + std::strerror(errno));
  int write_errno = write_all(fd, bytes);
  if (::close(fd) != 0 && write_errno == 0) write_errno = errno;
  if (write_errno != 0) {
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
    return io_error(path.string() + ": write failed: " + std::strerror(write_errno));
  }
  return {};
}

namespace {
constexpr std::size_t kWriterBufferBytes = std::size_t{1} << 20;
}  // namespace

// The open file of a NodeFileWriter: closed, and removed while unfinished, when it goes.
struct NodeFileWriter::File {
  File(std::filesystem::path p, UniqueFd descriptor) : path(std::move(p)), fd(std::move(descriptor)) {}
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  ~File() { abandon(); }

  void abandon() {  // closes and removes an unfinished file
    if (!fd.valid()) return;
    fd.reset();
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
  }
  Status write_buffer() {  // on error the file is abandoned
    if (const int error = write_all(fd.get(), buffer)) {
      abandon();
      return io_error(path.string() + ": write failed: " + std::strerror(error));
    }
    written += buffer.size();
    buffer.clear();
    return {};
  }
  Status flush() {  // buffer into the checksum, then written
    crc = crc32(buffer, crc);
    return write_buffer();
  }

  std::filesystem::path path;
  UniqueFd fd;
  std::size_t stride = 0;
  std::uint32_t index_bytes = 0;
  std::uint64_t vertices_left = 0;  // floats
  std::uint64_t indices_left = 0;
  std::uint32_t crc = 0;
  std::uint64_t written = 0;
  std::vector<std::byte> buffer;
};

Result<NodeFileWriter> NodeFileWriter::create(const std::filesystem::path& path,
                                              VertexLayout layout, std::uint32_t vertex_count,
                                              std::uint32_t index_count, const Bounds& bounds) {
  UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
  if (!fd.valid()) return io_error(path.string() + ": cannot create: " + std::strerror(errno));
  auto file = std::make_unique<File>(path, std::move(fd));
  file->stride = layout.floats();
  file->index_bytes = index_bytes_for(vertex_count);
  file->vertices_left = std::uint64_t{vertex_count} * file->stride;
  file->indices_left = index_count;
  file->buffer.reserve(kWriterBufferBytes);
  append_header(file->buffer, layout, vertex_count, index_count, bounds);
  return NodeFileWriter(std::move(file));
}

NodeFileWriter::NodeFileWriter(std::unique_ptr<File> file) : file_(std::move(file)) {}
NodeFileWriter::NodeFileWriter(NodeFileWriter&&) noexcept = default;
NodeFileWriter& NodeFileWriter::operator=(NodeFileWriter&&) noexcept = default;
NodeFileWriter::~NodeFileWriter() = default;

Status NodeFileWriter::append_vertices(std::span<const float> vertices) {
  File& f = *file_;
  assert(f.fd.valid() && "NodeFileWriter: used after an error or finish()");
  assert(vertices.size() % f.stride == 0 && vertices.size() <= f.vertices_left &&
         "NodeFileWriter: partial vertex or more vertices than declared");
  f.vertices_left -= vertices.size();
  const auto* bytes = reinterpret_cast<const std::byte*>(vertices.data());
  for (std::size_t done = 0; done < vertices.size_bytes();) {
    if (f.buffer.size() >= kWriterBufferBytes) OCTOLOD_RETURN_IF_ERROR(f.flush());
    const std::size_t n = std::min(vertices.size_bytes() - done, kWriterBufferBytes - f.buffer.size());
    f.buffer.insert(f.buffer.end(), bytes + done, bytes + done + n);
    done += n;
  }
  return {};
}

Status NodeFileWriter::append_indices(std::span<const std::uint32_t> indices) {
  File& f = *file_;
  assert(f.fd.valid() && "NodeFileWriter: used after an error or finish()");
  assert(f.vertices_left == 0 && indices.size() <= f.indices_left &&
         "NodeFileWriter: indices before the last vertex or more than declared");
  f.indices_left -= indices.size();
  constexpr std::size_t kBlock = kWriterBufferBytes / 8;  // indices appended between flushes
  for (std::size_t done = 0; done < indices.size(); done += kBlock) {
    if (f.buffer.size() + kBlock * f.index_bytes > kWriterBufferBytes) OCTOLOD_RETURN_IF_ERROR(f.flush());
    append_index_bytes(f.buffer, indices.subspan(done, std::min(kBlock, indices.size() - done)), f.index_bytes);
  }
  return {};
}

Result<std::uint64_t> NodeFileWriter::finish() {
  File& f = *file_;
  assert(f.fd.valid() && "NodeFileWriter: used after an error or finish()");
  assert(f.vertices_left == 0 && f.indices_left == 0 && "NodeFileWriter: fewer items than declared");
  OCTOLOD_RETURN_IF_ERROR(f.flush());
  detail::append_le(f.buffer, f.crc);  // the checksum covers everything before it
  OCTOLOD_RETURN_IF_ERROR(f.write_buffer());
  if (::close(f.fd.release()) != 0) {
    const int error = errno;
    std::error_code ignored;
    std::filesystem::remove(f.path, ignored);
    return io_error(f.path.string() + ": write failed: " + std::strerror(error));
  }
  return f.written;
}

namespace {

// The file at `path` read whole (node_file.h's read_node_file_bytes), its size checked against
// `expected_bytes` when there is one.
Result<std::vector<std::byte>> read_whole_file(const std::filesystem::path& path,
                                               std::optional<std::uint64_t> expected_bytes) {
  // O_NONBLOCK: opening a FIFO without a writer returns at once, and fstat then refuses it
  UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
  if (!fd.valid()) return io_error(path.string() + ": cannot open: " + std::strerror(errno));
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0) return io_error(path.string() + ": cannot stat: " + std::strerror(errno));
  if (!S_ISREG(info.st_mode)) return io_error(path.string() + ": not a regular file");
  const auto size = static_cast<std::uint64_t>(info.st_size);
  if (expected_bytes) OCTOLOD_RETURN_IF_ERROR(check_node_file_size(path.string(), size, *expected_bytes));
  std::vector<std::byte> bytes(static_cast<std::size_t>(size));
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::read(fd.get(), bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return io_error(path.string() + ": read failed: " + std::strerror(errno));
    if (n == 0) return io_error(path.string() + ": ended at byte " + std::to_string(done) + " while being read");
    done += static_cast<std::size_t>(n);
  }
  return bytes;
}

Result<NodeMesh> read_and_decode(const std::filesystem::path& path, std::optional<std::uint64_t> expected_bytes) {
  Result<std::vector<std::byte>> bytes = read_whole_file(path, expected_bytes);
  if (!bytes.ok()) return bytes.status();
  return decode_node_file(bytes.value(), path.string());
}

}  // namespace

Result<std::vector<std::byte>> read_node_file_bytes(const std::filesystem::path& path,
                                                    std::uint64_t expected_bytes) {
  return read_whole_file(path, expected_bytes);
}

Status check_node_file_size(std::string_view name, std::uint64_t actual_bytes, std::uint64_t expected_bytes) {
  if (actual_bytes == expected_bytes) return {};
  return bad_input_error(std::string(name) + ": " + std::to_string(actual_bytes) + " bytes, the manifest says " +
                         std::to_string(expected_bytes) + " (a node file from elsewhere, or an edited manifest)");
}

Result<NodeMesh> read_node_file(const std::filesystem::path& path) { return read_and_decode(path, std::nullopt); }

Result<NodeMesh> read_node_file(const std::filesystem::path& path, std::uint64_t expected_bytes) {
  return read_and_decode(path, expected_bytes);
}

}  // namespace octolod
