// The finished nodes' LOD records in a work file, see node_lods_log.h.
#include "node_lods_log.h"

#include <fcntl.h>
#include <unistd.h>

#include <cassert>
#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include "tree_paths.h"

namespace octolod::bake {
namespace {

// The record: a header, then one LodRecord per LOD, finest first (neither has padding: the
// file holds no uninitialized bytes).
struct RecordHeader {
  std::uint64_t prefix = 0;
  std::uint64_t triangles = 0;
  std::int32_t parent = -1;
  std::uint32_t depth = 0;
  std::array<std::int32_t, 8> children{};
  std::uint32_t leaf = 0;
  std::uint32_t lods = 0;
  Bounds bounds;
};
struct LodRecord {
  std::uint32_t triangles = 0;
  std::uint32_t vertices = 0;
  double error = 0;
  std::uint64_t bytes = 0;
};
static_assert(sizeof(RecordHeader) == 64 + sizeof(Bounds) && sizeof(LodRecord) == 24);

// Where node `node`'s stored offset is in the index file.
off_t index_position(std::int32_t node) {
  return static_cast<off_t>(std::uint64_t{static_cast<std::uint32_t>(node)} * sizeof(std::uint64_t));
}

}  // namespace

Result<NodeLodsLog> NodeLodsLog::create(const std::filesystem::path& work_dir) {
  NodeLodsLog log;
  log.file_ = make_temp_file(work_dir, "node-lods");
  auto writer = RecordWriter::create(log.file_.path(), 1, std::size_t{64} << 10);
  if (!writer.ok()) return writer.status();
  log.writer_.emplace(std::move(writer).value());
  log.index_file_ = make_temp_file(work_dir, "node-lods-index");
  log.index_fd_.reset(::open(log.index_file_.path().c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600));
  if (!log.index_fd_.valid())
    return io_error(log.index_file_.path().string() + ": cannot create: " + std::strerror(errno));
  return log;
}

Result<std::uint64_t> NodeLodsLog::stored_offset(std::int32_t node) const {
  std::uint64_t stored = 0;
  const off_t at = index_position(node);
  const ssize_t got = ::pread(index_fd_.get(), &stored, sizeof stored, at);
  if (got == 0) return std::uint64_t{0};  // past the end: never written
  if (got != static_cast<ssize_t>(sizeof stored))
    return io_error(index_file_.path().string() + ": node " + std::to_string(node) + ": cannot read offset " +
                    std::to_string(at) + (got < 0 ? std::string(": ") + std::strerror(errno) : ""));
  return stored;
}

Status NodeLodsLog::append(std::int32_t node, const NodeShape& shape, const NodeLods& lods) {
  assert(writer_ && node >= 0 && !has(node) && lods.lods.size() <= kMaxLods);
  const std::uint64_t stored = writer_->records_written() + 1;
  const off_t at = index_position(node);
  if (::pwrite(index_fd_.get(), &stored, sizeof stored, at) != static_cast<ssize_t>(sizeof stored))
    return io_error(index_file_.path().string() + ": cannot write at offset " + std::to_string(at) + ": " +
                    std::strerror(errno));
  const RecordHeader header{shape.prefix, shape.triangles, shape.parent,  shape.depth,
                            shape.children, shape.leaf ? 1u : 0u, static_cast<std::uint32_t>(lods.lods.size()),
                            lods.bounds};
  OCTOLOD_RETURN_IF_ERROR(writer_->append(reinterpret_cast<const std::byte*>(&header), sizeof header));
  for (const LodInfo& l : lods.lods) {
    const LodRecord r{l.triangles, l.vertices, l.error, l.bytes};
    OCTOLOD_RETURN_IF_ERROR(writer_->append(reinterpret_cast<const std::byte*>(&r), sizeof r));
  }
  return {};
}

Status NodeLodsLog::finish() {
  assert(writer_);
  OCTOLOD_RETURN_IF_ERROR(writer_->finish());
  writer_.reset();
  fd_.reset(::open(file_.path().c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd_.valid()) return io_error(file_.path().string() + ": cannot open: " + std::strerror(errno));
  return {};
}

bool NodeLodsLog::has(std::int32_t node) const {
  if (node < 0) return false;
  const Result<std::uint64_t> stored = stored_offset(node);
  return stored.ok() && stored.value() != 0;
}

Result<LoggedNode> NodeLodsLog::read(std::int32_t node) const {
  assert(fd_.valid() && node >= 0);
  const Result<std::uint64_t> stored = stored_offset(node);
  if (!stored.ok()) return stored.status();
  if (stored.value() == 0)
    return io_error(index_file_.path().string() + ": node " + std::to_string(node) + " was never recorded");
  const std::uint64_t offset = stored.value() - 1;
  const auto read_at = [&](void* dst, std::size_t bytes, std::uint64_t at) -> Status {
    const ssize_t got = ::pread(fd_.get(), dst, bytes, static_cast<off_t>(at));
    if (got == static_cast<ssize_t>(bytes)) return {};
    return io_error(file_.path().string() + ": node " + std::to_string(node) +
                    ": cannot read " + std::to_string(bytes) + " bytes at offset " +
                    std::to_string(at) + (got < 0 ? std::string(": ") + std::strerror(errno) : ""));
  };
  RecordHeader header;
  OCTOLOD_RETURN_IF_ERROR(read_at(&header, sizeof header, offset));
  if (header.lods > kMaxLods) {
    return io_error(file_.path().string() + ": node " + std::to_string(node) + ": " +
                    std::to_string(header.lods) + " LODs at offset " + std::to_string(offset));
  }
  std::vector<LodRecord> records(header.lods);
  OCTOLOD_RETURN_IF_ERROR(
      read_at(records.data(), records.size() * sizeof(LodRecord), offset + sizeof header));
  LoggedNode logged;
  logged.shape = {header.prefix, header.triangles, header.parent, header.depth, header.children, header.leaf != 0};
  const std::string dir = node_path(header.prefix, header.depth);
  NodeLods& lods = logged.lods;
  lods.bounds = header.bounds;
  lods.lods.reserve(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    const LodRecord& r = records[i];
    lods.lods.push_back(LodInfo{r.triangles, r.vertices, r.error, r.bytes, lod_file_name(dir, i)});
  }
  return logged;
}

}  // namespace octolod::bake
