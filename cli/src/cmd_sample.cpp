// octolod sample: writes a deterministic procedural mesh (rock, terrain, city, tube) of about N
// triangles as PLY, streaming, so any N runs in a few MB (see octolod/samplegen).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <thread>

#include "command.h"
#include "commands.h"
#include "octolod/bake/temp_dir.h"
#include "octolod/formats/output_file.h"
#include "octolod/samplegen/sample_generator.h"
#include "image.h"
#include "progress.h"

namespace octolod::cli {
namespace {

// The sample's texture: six hue bands along u (red, yellow, green, cyan, blue, magenta), a
// checker of 16 x 8 cells dimming every other one, so that a render shows where the UVs run and
// where they are cut (the rock's u = 0 / 1 seam, the city's tiles).
Image sample_texture() {
  constexpr int kWidth = 1024, kHeight = 512;
  constexpr std::uint32_t kBands[6] = {0xe04040, 0xe0c030, 0x40c050, 0x30b0d0, 0x4060e0, 0xc040c0};
  Image image(kWidth, kHeight, 0);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const std::uint32_t band = kBands[x * 6 / kWidth];
      const bool dim = ((x * 16 / kWidth) + (y * 8 / kHeight)) % 2 == 1;
      const auto channel = [&](int shift) {
        const std::uint32_t c = (band >> shift) & 0xFFu;
        return (dim ? c * 5 / 8 : c) << shift;
      };
      image.set(x, y, channel(16) | channel(8) | channel(0));
    }
  return image;
}

}  // namespace

int run_sample(const SampleArgs& args, const CommandContext& context) {
  using namespace octolod::samplegen;
  SampleSpec spec;
  Result<Shape> shape = parse_shape(args.shape);
  if (!shape.ok()) return report(shape.status());
  spec.shape = shape.value();
  Result<std::uint64_t> triangles = parse_triangle_count(args.triangles);
  if (!triangles.ok()) return report(triangles.status());
  spec.triangles = triangles.value();
  Result<VertexLayout> layout = parse_attributes(args.attributes);
  if (!layout.ok()) return report(layout.status());
  spec.layout = layout.value();
  spec.seed = args.seed;
  for (std::size_t k = 0; k < args.offset.size() && k < 3; ++k) {
    if (!std::isfinite(args.offset[k])) return report(usage_error("--offset: every coordinate must be finite"));
    spec.offset[k] = args.offset[k];
  }
  Result<SampleCounts> counts = sample_counts(spec);
  if (!counts.ok()) return report(counts.status());
  std::filesystem::path texture;  // next to the output: OUT.png
  if (args.texture) {
    if (!spec.layout.uv) return report(usage_error("--texture: the sample has no uv to index it (--attributes)"));
    texture = std::filesystem::path(args.output).replace_extension(".png");
    spec.texture_file = texture.filename().string();
  }

  // Written inside a temporary directory next to the output, then renamed into place: SIGINT or
  // SIGTERM removes it (and a later run one left by a killed process), so a large sample
  // interrupted leaves nothing behind.
  if (const Status usable = check_output_file(args.output, "the sample"); !usable.ok()) return report(usable);
  const std::filesystem::path output = std::filesystem::absolute(args.output);
  bake::install_signal_cleanup();
  bake::remove_stale_temp_dirs(output.parent_path());
  Result<bake::TempDir> staging = bake::TempDir::create(output.parent_path(), "sample");
  if (!staging.ok()) return report(staging.status());
  const std::filesystem::path staged = staging->path() / output.filename();

  Progress progress(context);
  const auto start = std::chrono::steady_clock::now();
  const Status written = write_sample_ply(
      spec, staged, args.ascii ? PlyFormat::ascii : PlyFormat::binary_little_endian,
      [&](std::uint64_t done, std::uint64_t total) { progress.update("sample", done, total); },
      SampleStreamOptions{.threads = std::max(1u, std::thread::hardware_concurrency())});
  if (bake::cleanup_signal_received()) bake::await_signal_cleanup();
  if (!written.ok()) return report(written);
  if (!texture.empty()) {
    const std::filesystem::path staged_texture = staging->path() / texture.filename();
    if (const Status image = write_png(staged_texture, sample_texture()); !image.ok()) return report(image);
    std::error_code moved;
    std::filesystem::rename(staged_texture, std::filesystem::absolute(texture), moved);
    if (moved) return report(io_error(texture.string() + ": cannot write: " + moved.message()));
  }
  std::error_code renamed;
  std::filesystem::rename(staged, output, renamed);
  if (renamed) return report(io_error(args.output + ": cannot write: " + renamed.message()));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.finish("sample", seconds);

  const Result<std::uint64_t> written_bytes = written_file_size(args.output);
  if (!written_bytes.ok()) return report(written_bytes.status());
  const std::uint64_t bytes = written_bytes.value();
  if (context.json) {
    print_json({{"file", args.output},
                {"shape", std::string(to_string(spec.shape))},
                {"vertices", counts->vertices},
                {"triangles", counts->triangles},
                {"attributes", spec.layout.describe()},
                {"texture", texture.string()},
                {"bytes", bytes},
                {"seconds", seconds}});
  } else {
    std::printf("%s: %s, %llu vertices, %llu triangles (%s), %.1f MB in %.2f s\n",
                args.output.c_str(), std::string(to_string(spec.shape)).c_str(),
                static_cast<unsigned long long>(counts->vertices),
                static_cast<unsigned long long>(counts->triangles), spec.layout.describe().c_str(),
                static_cast<double>(bytes) / 1e6, seconds);
  }
  return 0;
}


}  // namespace octolod::cli
