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

constexpr std::uint64_t kAbsent = ~std::uint64_t{0};

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

}  // namespace

Result<NodeLodsLog> NodeLodsLog::create(const std::filesystem::path& work_dir) {
  NodeLodsLog log;
  log.file_ = make_temp_file(work_dir, "node-lods");
  auto writer = RecordWriter::create(log.file_.path(), 1, std::size_t{64} << 10);
  if (!writer.ok()) return writer.status();
  log.writer_.emplace(std::move(writer).value());
  return log;
}

NodeLodsLog::NodeLodsLog(NodeLodsLog&& other) noexcept
    : file_(std::move(other.file_)),
      writer_(std::move(other.writer_)),
      fd_(std::exchange(other.fd_, -1)),
      offsets_(std::move(other.offsets_)) {
  other.writer_.reset();
}

NodeLodsLog& NodeLodsLog::operator=(NodeLodsLog&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    writer_.reset();  // before the file it writes is removed
    file_ = std::move(other.file_);
    writer_ = std::move(other.writer_);
    other.writer_.reset();
    fd_ = std::exchange(other.fd_, -1);
    offsets_ = std::move(other.offsets_);
  }
  return *this;
}

NodeLodsLog::~NodeLodsLog() {
  if (fd_ >= 0) ::close(fd_);
  writer_.reset();
}

Status NodeLodsLog::append(std::int32_t node, const NodeShape& shape, const NodeLods& lods) {
  assert(writer_ && node >= 0 && !has(node) && lods.lods.size() <= kMaxLods);
  const auto index = static_cast<std::size_t>(node);
  if (offsets_.size() <= index) offsets_.resize(index + 1, kAbsent);
  offsets_[index] = writer_->records_written();
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
  fd_ = ::open(file_.path().c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) return io_error(file_.path().string() + ": cannot open: " + std::strerror(errno));
  return {};
}

bool NodeLodsLog::has(std::int32_t node) const {
  const auto index = static_cast<std::size_t>(node);
  return node >= 0 && index < offsets_.size() && offsets_[index] != kAbsent;
}

Result<LoggedNode> NodeLodsLog::read(std::int32_t node) const {
  assert(fd_ >= 0 && has(node));
  const std::uint64_t offset = offsets_[static_cast<std::size_t>(node)];
  const auto read_at = [&](void* dst, std::size_t bytes, std::uint64_t at) -> Status {
    const ssize_t got = ::pread(fd_, dst, bytes, static_cast<off_t>(at));
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
