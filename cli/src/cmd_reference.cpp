// octolod reference: the QSlim-style baseline (Garland & Heckbert 1997) a baked LOD is compared
// against — OpenMesh's Decimater with the quadric module, a normal-flip guard and a valence limit
// (octolod/measure/reference.h) — at a given triangle count, written as PLY.
//
// Exit codes: 1 usage, 2 malformed input or no triangles, 4 the input cannot be read or the
// output written (nothing is left behind then).
#include <cstdio>
#include <string>

#include "command.h"
#include "commands.h"
#include "mesh_file.h"
#include "octolod/measure/reference.h"
#include "progress.h"

namespace octolod::cli {

int run_reference(const ReferenceArgs& args, const CommandContext& context) {
  Progress progress(context);
  Result<MeshFile> input = read_mesh_file(args.input);
  if (!input.ok()) return report(input.status());
  progress.message("reference: decimating " + std::to_string(input->mesh.triangle_count()) +
                   " triangles to " + std::to_string(args.triangles));
  measure::ReferenceStats stats;
  Result<NodeMesh> simplified = measure::reference_simplify(input->mesh, args.triangles, &stats);
  if (!simplified.ok())
    return report(Status(simplified.status().code(),
                         args.input + ": " + simplified.status().message()));
  progress.finish("reference", stats.seconds);
  const Status written =
      write_mesh_file(args.output, simplified.value(), args.ascii, input->color_type, input->origin);
  if (!written.ok()) return report(written);

  const Result<std::uint64_t> written_bytes = written_file_size(args.output);
  if (!written_bytes.ok()) return report(written_bytes.status());
  const std::uint64_t bytes = written_bytes.value();
  if (context.json) {
    print_json({{"file", args.output},
                {"input", args.input},
                {"input_triangles", stats.input_triangles},
                {"target_triangles", args.triangles},
                {"triangles", simplified->triangle_count()},
                {"vertices", simplified->vertex_count()},
                {"welded_vertices", stats.welded_vertices},
                {"detached_triangles", stats.detached_triangles},
                {"layout", simplified->layout.describe()},
                {"bytes", bytes},
                {"seconds", stats.seconds}});
  } else {
    const std::string detached =
        stats.detached_triangles ? ", " + std::to_string(stats.detached_triangles) +
                                       " non-manifold triangles kept unsimplified"
                                 : "";
    std::printf("%s: %llu -> %zu triangles (target %u), %zu vertices%s in %.2f s\n",
                args.output.c_str(), static_cast<unsigned long long>(stats.input_triangles),
                simplified->triangle_count(), args.triangles, simplified->vertex_count(),
                detached.c_str(), stats.seconds);
  }
  return 0;
}


}  // namespace octolod::cli
