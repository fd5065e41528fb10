// Benchmark of the triangle soup stage (seed 3.3, 4.2, Table 4.1): generates a sample PLY once
// (in a child process, so its memory does not count), then runs build_soup and prints
// triangles/s, seconds per stage, the sorts' shape and the peak RSS (getrusage).
//
//   soup_bench [--triangles 1M] [--memory 64M] [--threads 2] [--shape terrain]
//              [--attributes normal,color,uv] [--order any|triangle] [--out-of-core]
//              [--work DIR] [--repeat N] [--sink]
// --sink hands the soup to a callback (as the octree stage can) instead of writing the file.
// The PLY is cached in the work directory as soup-bench-<shape>-<triangles>-<mask>.ply.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include "octolod/bake/soup.h"
#include "octolod/samplegen/sample_generator.h"
#include "peak_rss_mib.h"

namespace {

using namespace octolod;

std::uint64_t sink_bytes = 0;  // soup bytes handed to the --sink callback

bool parse_bytes(std::string_view text, std::uint64_t& out) {
  if (text.empty()) return false;
  std::uint64_t unit = 1;
  switch (text.back()) {
    case 'K': case 'k': unit = 1ull << 10; break;
    case 'M': case 'm': unit = 1ull << 20; break;
    case 'G': case 'g': unit = 1ull << 30; break;
    default: break;
  }
  if (unit != 1) text.remove_suffix(1);
  char* end = nullptr;
  const std::string s(text);
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0' || v <= 0) return false;
  out = static_cast<std::uint64_t>(v * static_cast<double>(unit));
  return true;
}

int fail(const std::string& message) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return 2;
}

// Writes the sample in a child process so the generator's memory stays out of our peak RSS.
bool generate(const samplegen::SampleSpec& spec, const std::filesystem::path& path) {
  const pid_t pid = ::fork();
  if (pid < 0) return false;
  if (pid == 0) {
    samplegen::SampleStreamOptions stream;
    stream.threads = 2;
    const Status st = samplegen::write_sample_ply(spec, path, PlyFormat::binary_little_endian, {},
                                                  stream);
    if (!st.ok()) std::fprintf(stderr, "error: %s\n", st.message().c_str());
    std::_Exit(st.ok() ? 0 : 1);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  samplegen::SampleSpec spec;
  spec.shape = samplegen::Shape::terrain;
  spec.triangles = 1'000'000;
  bake::SoupOptions options;
  options.memory_budget_bytes = 64ull << 20;
  std::filesystem::path work = std::filesystem::temp_directory_path();
  int repeat = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    const std::string_view value = has_value ? argv[i + 1] : "";
    if (arg == "--triangles" && has_value) {
      auto n = samplegen::parse_triangle_count(value);
      if (!n.ok()) return fail(n.status().message());
      spec.triangles = n.value();
    } else if (arg == "--memory" && has_value) {
      if (!parse_bytes(value, options.memory_budget_bytes)) return fail("bad --memory");
    } else if (arg == "--threads" && has_value) {
      options.threads = static_cast<unsigned>(std::atoi(std::string(value).c_str()));
    } else if (arg == "--shape" && has_value) {
      auto s = samplegen::parse_shape(value);
      if (!s.ok()) return fail(s.status().message());
      spec.shape = s.value();
    } else if (arg == "--attributes" && has_value) {
      auto a = samplegen::parse_attributes(value);
      if (!a.ok()) return fail(a.status().message());
      spec.layout = a.value();
    } else if (arg == "--order" && has_value) {
      options.order = value == "triangle" ? bake::SoupOrder::by_triangle : bake::SoupOrder::any;
    } else if (arg == "--work" && has_value) {
      work = value;
    } else if (arg == "--repeat" && has_value) {
      repeat = std::max(1, std::atoi(std::string(value).c_str()));
    } else if (arg == "--out-of-core") {
      options.force_out_of_core = true;
      continue;
    } else if (arg == "--sink") {
      options.sink = [](std::span<const std::byte> records) {
        sink_bytes += records.size();
        return Status{};
      };
      continue;
    } else {
      return fail("unknown or incomplete argument '" + std::string(arg) + "'");
    }
    ++i;
  }
  options.work_dir = work;
  const std::filesystem::path ply =
      work / ("soup-bench-" + std::string(samplegen::to_string(spec.shape)) + "-" +
              std::to_string(spec.triangles) + "-" + std::to_string(spec.layout.mask()) + ".ply");
  if (!std::filesystem::exists(ply)) {
    std::printf("generating %s\n", ply.c_str());
    if (!generate(spec, ply)) return fail("could not generate " + ply.string());
  }
  std::printf("input %s (%.1f MiB), memory %.1f MiB, threads %u, order %s%s\n", ply.c_str(),
              static_cast<double>(std::filesystem::file_size(ply)) / (1 << 20),
              static_cast<double>(options.memory_budget_bytes) / (1 << 20), options.threads,
              options.order == bake::SoupOrder::by_triangle ? "triangle" : "any",
              options.force_out_of_core ? ", forced out of core" : "");
  for (int r = 0; r < repeat; ++r) {
    auto result = bake::build_soup(ply, options);
    if (!result.ok()) return fail(result.status().message());
    const bake::SoupResult& s = result.value();
    std::printf(
        "%s: %llu triangles, %llu vertices, layout %s: %.3f s total = split %.3f + sort %.3f + "
        "dereference %.3f; %.2f M triangles/s; soup %.1f MiB%s\n",
        s.in_core ? "in core" : "out of core", static_cast<unsigned long long>(s.triangle_count),
        static_cast<unsigned long long>(s.vertex_count), s.layout.describe().c_str(),
        s.seconds.total, s.seconds.split, s.seconds.sort, s.seconds.dereference,
        static_cast<double>(s.triangle_count) / s.seconds.total / 1e6,
        static_cast<double>(s.soup.empty() ? sink_bytes : std::filesystem::file_size(s.soup.path())) /
            (1 << 20),
        s.soup.empty() ? " (sink)" : "");
    if (!s.in_core) {
      std::printf("  window pass: %llu far triangles left to the sorted passes\n",
                  static_cast<unsigned long long>(s.far_triangles));
    }
    sink_bytes = 0;
    for (const bake::SortStats& st : s.sorts) {
      std::printf(
          "  sort: %llu records, %s, %llu runs, %u merge passes, fan-in %u, %.1f MiB written, "
          "%.3f s\n",
          static_cast<unsigned long long>(st.records), st.in_core ? "in core" : "external",
          static_cast<unsigned long long>(st.runs), st.merge_passes, st.fan_in,
          static_cast<double>(st.bytes_written) / (1 << 20), st.seconds);
    }
  }
  std::printf("peak RSS %.1f MiB\n", peak_rss_mib());
  return 0;
}
