// octolod eval: Metro-style comparison of two meshes (Cignoni, Rocchini, Scopigno 1998): both
// surfaces sampled uniformly by area, every sample's exact distance to the other surface
// (octolod/measure/metro.h). Reports mean, RMS and max one way, the other way and pooled (the
// max pooled is the Hausdorff distance), absolute (model units) and relative to the bounding-box
// diagonal of A, plus normal-angle, colour and uv deviation at the samples when both have them.
// With --picture, B coloured by its distance to A next to A coloured by its distance to B
// (error_picture.h).
//
// Exit codes: 1 usage, 2 a file is malformed or has no triangles/area, 4 a file cannot be read.
#include <cstdio>
#include <filesystem>
#include <string>

#include "command.h"
#include "commands.h"
#include "error_picture.h"
#include "mesh_file.h"
#include "metro_json.h"
#include "octolod/formats/output_file.h"
#include "octolod/measure/metro.h"
#include "progress.h"

namespace octolod::cli {
namespace {

void print_deviation(const char* name, const measure::Deviation& d) {
  std::printf("%-9s %9llu  mean %.6g (%.4f%%)  rms %.6g (%.4f%%)  max %.6g (%.4f%%)\n", name,
              static_cast<unsigned long long>(d.samples), d.mean, 100.0 * d.mean_relative, d.rms,
              100.0 * d.rms_relative, d.max, 100.0 * d.max_relative);
  if (d.samples > 0)
    std::printf("%-9s max at (%.9g %.9g %.9g), closest (%.9g %.9g %.9g)\n", "", d.max_at[0], d.max_at[1],
                d.max_at[2], d.max_closest[0], d.max_closest[1], d.max_closest[2]);
  if (d.compared.normal)
    std::printf("%-9s normal angle mean %.3f deg, max %.3f deg\n", "", d.normal_mean_degrees,
                d.normal_max_degrees);
  if (d.compared.color) std::printf("%-9s colour rms %.6g\n", "", d.color_rms);
  if (d.compared.uv) std::printf("%-9s uv rms %.6g\n", "", d.uv_rms);
}

// The picture of B to A and A to B, from the overview camera of both meshes' bounds, with the
// given top of its colour scale (0: its largest distance); that scale.
Result<double> write_picture(const std::string& path, const NodeMesh& a, const NodeMesh& b, double scale) {
  const measure::TriangleBvh a_surface(a.vertices, a.layout.floats(), a.indices);
  const measure::TriangleBvh b_surface(b.vertices, b.layout.floats(), b.indices);
  const ErrorPanel panels[] = {{&b, &a_surface, "B TO A"}, {&a, &b_surface, "A TO B"}};
  Bounds frame = a.bounds();
  frame.extend(b.bounds());
  Result<ErrorPicture> picture = render_error_picture(panels, 2, frame, scale);
  if (!picture.ok()) return picture.status();
  OCTOLOD_RETURN_IF_ERROR(write_png(path, picture->image));
  return picture->scale;
}

}  // namespace

int run_eval(const EvalArgs& args, const CommandContext& context) {
  Progress progress(context);
  if (!args.picture.empty()) {  // before the long work: a picture that has nowhere to go fails now
    if (const Status usable = check_output_file(args.picture, "the picture"); !usable.ok()) return report(usable);
  }
  Result<MeshFile> a = read_mesh_file(args.a);
  if (!a.ok()) return report(a.status());
  Result<MeshFile> b = read_mesh_file(args.b, a->origin);  // both in a's frame
  if (!b.ok()) return report(b.status());
  progress.message("eval: read " + std::to_string(a->mesh.triangle_count()) + " + " +
                   std::to_string(b->mesh.triangle_count()) + " triangles");

  measure::MetroOptions options;
  options.samples = args.samples;
  options.seed = args.seed;
  options.threads = args.threads;
  Result<measure::MetroReport> r = measure::evaluate(a->mesh, b->mesh, options);
  if (!r.ok())  // the library names the meshes "mesh a" / "mesh b"
    return report(Status(r.status().code(),
                         r.status().message() + " (a = " + args.a + ", b = " + args.b + ")"));
  progress.finish("eval", r->seconds);
  place_maxima(r.value(), a->origin);
  double picture_scale = 0.0;
  if (!args.picture.empty()) {
    progress.message("eval: picture");
    Result<double> scale = write_picture(args.picture, a->mesh, b->mesh, args.picture_scale);
    if (!scale.ok()) return report(scale.status());
    picture_scale = scale.value();
  }

  if (context.json) {
    nlohmann::json j = metro_json(r.value());
    j["a"] = {{"file", args.a},
              {"triangles", a->mesh.triangle_count()},
              {"layout", a->mesh.layout.describe()}};
    j["b"] = {{"file", args.b},
              {"triangles", b->mesh.triangle_count()},
              {"layout", b->mesh.layout.describe()}};
    j["seed"] = args.seed;
    if (!args.picture.empty()) j["picture"] = {{"file", args.picture}, {"scale", picture_scale}};
    print_json(j);
    return 0;
  }
  std::printf("a: %s, %zu triangles (%s), area %.6g\n", args.a.c_str(), a->mesh.triangle_count(),
              a->mesh.layout.describe().c_str(), r->area_a);
  std::printf("b: %s, %zu triangles (%s), area %.6g\n", args.b.c_str(), b->mesh.triangle_count(),
              b->mesh.layout.describe().c_str(), r->area_b);
  std::printf("distances in model units (%% of a's bounding-box diagonal %.6g):\n", r->diagonal);
  print_deviation("a -> b", r->a_to_b);
  print_deviation("b -> a", r->b_to_a);
  print_deviation("two-sided", r->two_sided);
  std::printf("Hausdorff %.6g, %u threads, %.2f s\n", r->two_sided.max, r->threads, r->seconds);
  if (!args.picture.empty())
    std::printf("picture %s: b to a, a to b, colours 0 .. %.4g model units\n", args.picture.c_str(), picture_scale);
  return 0;
}


}  // namespace octolod::cli
