// Every subcommand's options, help text and checks, declared with CLI11. The only file besides
// main.cpp that includes CLI11: Debian's CLI11 2.1 is header-only and instantiating it costs
// ~15-20 s of compile time per file, once per build type, so the commands themselves
// (cmd_<name>.cpp) take plain argument structs (commands.h).
#include "command_line.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "octolod/bake/bake.h"

namespace octolod::cli {
namespace {

// Caps of counts the user gives, so that a typo fails as a usage error instead of exhausting
// threads or memory: more threads than this gains nothing, and a sample costs time, not memory,
// beyond 1e9 (hours per direction).
constexpr unsigned kMaxThreads = 1024;
constexpr std::uint64_t kMaxSamples = 1'000'000'000;

// A validator of numbers: `message` unless accept(value). Text that is not a number passes, for
// the option's conversion to report.
CLI::Validator number_check(bool (*accept)(double), const char* message, const char* description) {
  return CLI::Validator(
      [=](const std::string& text) {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        const bool number = end != text.c_str() && *end == '\0';
        return !number || accept(value) ? std::string() : std::string(message);
      },
      description);
}

// An item of a comma-separated list that is not empty (CLI11 reads "" as 0: "0.1,,0.2" would
// add a target of 0).
CLI::Validator non_empty_item() {
  return CLI::Validator([](const std::string& text) { return text.empty() ? std::string("an empty item") : std::string(); },
                        "");
}

// A finite number > 0 (CLI::PositiveNumber lets NaN through).
CLI::Validator positive_finite() {
  return number_check([](double v) { return v > 0.0 && std::isfinite(v); }, "must be finite and > 0", "> 0");
}

// The mutually exclusive --error and --level options of a uniform cut, stored into `choice`
// (which must outlive the parse); check_cut_choice checks them once parsed.
void add_cut_options(CLI::App& command, CutChoice& choice) {
  CLI::Option* error =
      command.add_option("--error", choice.error,
                         "Per node, the coarsest LOD whose stored error is <= E (model units)");
  CLI::Option* level = command.add_option(
      "--level", choice.level, "The nodes at octree depth K (and leaves above it), finest LOD each; K at most the tree's deepest level");
  error->excludes(level);
}

void add_bake_command(CLI::App& app, CommandContext& context) {
  auto args = std::make_shared<BakeArgs>();
  CLI::App* command = app.add_subcommand(
      "bake", "Bake a PLY mesh into an on-disk LOD octree directory (bounded memory)");
  command->add_option("input", args->input,
                      "Input .ply file (UVs per vertex or per face corner; the image a 'comment TextureFile NAME' "
                      "line names next to it is copied into the tree)")
      ->required();
  command->add_option("-o,--output", args->output,
                      "Output directory (created; an earlier bake there is replaced atomically)")
      ->required();
  command
      ->add_option("--max-tris", args->max_tris,
                   "A node splits while it holds more triangles than this")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1u << 30));
  command
      ->add_option("--max-depth", args->max_depth,
                   "Deepest octree level (root = 0); leaves there keep all their triangles, "
                   "and one holding more than a quarter of --memory can simplify in memory is "
                   "built streaming from a temporary file (its LOD 1 at most that many triangles)")
      ->capture_default_str()
      ->check(CLI::Range(0u, 21u));
  command
      ->add_option("--memory", args->memory,
                   "Peak memory (RSS) of the whole process: 48M, 64M, 1G (the program itself "
                   "takes 8M of it; about 46M at least at --max-tris 2000 with every attribute: "
                   "a budget too small is refused with one that suffices)")
      ->capture_default_str();
  command->add_option("--work-dir", args->work_dir,
                      "Directory for temporary files (default: next to the output)");
  command->add_option("--threads", args->threads,
                      "Worker threads, up to 1024; each past the second takes 128 KiB of --memory (default or 0: all "
                      "cores, fewer if the budget cannot hold them)")
      ->check(CLI::Range(0u, kMaxThreads));
  command
      ->add_option("--method", args->method,
                   "Clustering of the LODs: grid (cells inside each node) or bade2006 (the "
                   "seed's one representative per node); none: leaves keep only their original "
                   "triangles")
      ->capture_default_str()
      ->check(CLI::IsMember({"grid", "bade2006", "none"}));
  command
      ->add_option("--lod-ratio", args->lod_ratio,
                   "Each LOD has at most this fraction of the previous LOD's triangles; lower: fewer "
                   "LODs and a smaller tree, with coarser steps for a runtime to choose from (the 1M "
                   "rock at 0.25: half the bake time, 56% of the bytes; docs/benchmarks.md, \"The "
                   "LOD ratio\")")
      ->capture_default_str()
      ->check(CLI::Range(bake::kMinLodRatio, bake::kMaxLodRatio));
  command->add_flag("--out-of-core", args->out_of_core,
                    "Take the out-of-core soup path even when the vertices fit the budget");
  command->callback([args, &context] { context.exit_code = run_bake(*args, context); });
}

void add_compare_command(CLI::App& app, CommandContext& context) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* command = app.add_subcommand(
      "compare",
      "Uniform cuts of a baked tree vs its input, next to the QSlim-style reference at the same "
      "triangle counts (two-sided RMS and Hausdorff)");
  command->add_option("input", args->input, "The .ply the tree was baked from")->required();
  command->add_option("tree", args->tree, "Baked tree directory (holds manifest.json)")->required();
  CLI::Option* errors =
      command
          ->add_option("--errors", args->errors,
                       "Comma-separated error targets (model units), one uniform cut each")
          ->delimiter(',')
          ->check(non_empty_item());
  command
      ->add_option("--fractions", args->fractions,
                   "Without --errors: cuts closest to these fractions of the input's triangles, "
                   "chosen among the tree's stored LOD errors")
      ->delimiter(',')
      ->check(non_empty_item())
      ->capture_default_str()
      ->excludes(errors);
  command
      ->add_option("--samples", args->samples,
                   "Metro samples per direction, up to 1e9; 0 = 10 per triangle, 100K..1M")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t{0}, kMaxSamples));
  command->add_flag("--markdown", args->markdown, "Print the table as Markdown");
  command->add_flag("--no-reference", args->no_reference,
                    "Skip the reference decimation (the cut columns only; much faster on "
                    "large inputs)");
  CLI::Option* pictures = command->add_option(
      "--pictures", args->pictures,
      "Directory (created) for one PNG per cut, framed like render's overview: the "
      "cut coloured by its distance to the input next to the input coloured by its "
      "distance to the cut, and a row the same for the reference (blue none, red "
      "the picture's largest)");
  command
      ->add_option("--picture-scale", args->picture_scale,
                   "Distance (model units) at the red end of the pictures' colour scale, the same "
                   "for every picture (default: each picture's largest)")
      ->check(positive_finite())
      ->needs(pictures);
  command->callback([args, &context] { context.exit_code = run_compare(*args, context); });
}

void add_eval_command(CLI::App& app, CommandContext& context) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* command = app.add_subcommand(
      "eval", "Metro-style distance between two meshes: mean, RMS, max (Hausdorff) and where it is, "
              "both ways, plus normal/colour/uv deviation");
  command->add_option("a", args->a, "First mesh (.ply); relative numbers use its diagonal")
      ->required();
  command->add_option("b", args->b, "Second mesh (.ply)")->required();
  command
      ->add_option("--samples", args->samples,
                   "Samples per direction, up to 1e9; 0 = 10 per triangle of the sampled mesh, "
                   "100K..1M")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t{0}, kMaxSamples));
  command->add_option("--seed", args->seed, "Sample generator seed (same seed, same numbers)")
      ->capture_default_str();
  command->add_option("--threads", args->threads,
                      "Query threads, up to 1024 (default or 0: all cores; the numbers do not depend on it)")
      ->check(CLI::Range(0u, kMaxThreads));
  CLI::Option* picture = command->add_option(
      "--picture", args->picture,
      "PNG of B coloured by its distance to A next to A coloured by its distance "
      "to B, framed like render's overview (blue none, red the largest)");
  command
      ->add_option("--picture-scale", args->picture_scale,
                   "Distance (model units) at the red end of the picture's colour scale (default: "
                   "its largest)")
      ->check(positive_finite())
      ->needs(picture);
  command->callback([args, &context] { context.exit_code = run_eval(*args, context); });
}

void add_export_command(CLI::App& app, CommandContext& context) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* command = app.add_subcommand(
      "export", "Write a uniform cut of a baked tree as glTF/GLB, one mesh per node LOD");
  command->add_option("tree", args->tree, "Baked tree directory (holds manifest.json)")->required();
  add_cut_options(*command, args->cut);
  command->add_option("-o,--output", args->output, "Output file: .glb, or .gltf for embedded JSON")
      ->required()
      ->check(CLI::Validator(
          [](const std::string& name) {
            const std::string extension = std::filesystem::path(name).extension().string();
            return extension == ".glb" || extension == ".gltf" ? std::string()
                                                               : std::string("must end in .glb or .gltf");
          },
          "FILE.glb|FILE.gltf"));
  CLI::Option* draco = command->add_flag(
      "--draco", args->draco,
      "Compress with Draco (KHR_draco_mesh_compression; lossy, see --position-bits)");
  command
      ->add_option("--position-bits", args->draco_options.position_bits,
                   "Draco position quantization bits (1..24; 0 keeps float positions) over the cut's bounding cube")
      ->capture_default_str()
      ->needs(draco);
  command->callback([args, &context] {
    if (const Status choice = check_cut_choice(args->cut, "export"); !choice.ok()) {
      context.exit_code = report(choice);
      return;
    }
    context.exit_code = run_export(*args, context);
  });
}

void add_extract_command(CLI::App& app, CommandContext& context) {
  auto args = std::make_shared<ExtractArgs>();
  CLI::App* command = app.add_subcommand(
      "extract", "Write the mesh of a uniform cut of a baked tree as one welded PLY");
  command->add_option("tree", args->tree, "Baked tree directory (holds manifest.json)")->required();
  add_cut_options(*command, args->cut);
  command->add_option("-o,--output", args->output, "Output .ply file (written atomically)")
      ->required();
  command->add_flag("--ascii", args->ascii, "Write ascii PLY (default: binary little-endian)");
  command->callback([args, &context] {
    if (const Status choice = check_cut_choice(args->cut, "extract"); !choice.ok()) {
      context.exit_code = report(choice);
      return;
    }
    context.exit_code = run_extract(*args, context);
  });
}

void add_info_command(CLI::App& app, CommandContext& context) {
  auto tree = std::make_shared<std::string>();
  CLI::App* command = app.add_subcommand(
      "info",
      "Summarize a baked tree (nodes, leaves, LODs with triangles and errors, sizes, parameters, times), or "
      "what octolod reads from a PLY file (its header: counts, attributes and where they come from, textures, "
      "what is skipped)");
  command->add_option("path", *tree, "Baked tree directory (holds manifest.json), or a PLY file")->required();
  command->callback([tree, &context] { context.exit_code = run_info(*tree, context); });
}

void add_reference_command(CLI::App& app, CommandContext& context) {
  auto args = std::make_shared<ReferenceArgs>();
  CLI::App* command = app.add_subcommand(
      "reference",
      "QSlim-style reference simplification (OpenMesh Decimater, quadrics + normal-flip guard, valence <= 16)");
  command->add_option("input", args->input, "Input mesh (.ply)")->required();
  command
      ->add_option("--triangles", args->triangles,
                   "Target triangle count (reached exactly or one below on closed meshes; "
                   "boundaries and non-manifold parts can stop above it)")
      ->required()
      ->check(CLI::Range(1u, 0xFFFFFFFFu));
  command->add_option("-o,--output", args->output, "Output .ply file (written atomically)")
      ->required();
  command->add_flag("--ascii", args->ascii, "Write ascii PLY (default: binary little-endian)");
  command->callback([args, &context] { context.exit_code = run_reference(*args, context); });
}

void add_render_command(CLI::App& app, CommandContext& context) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* command = app.add_subcommand(
      "render", "Render a baked tree as the streaming runtime selects it, nodes tinted by detail level (PNG)");
  command->add_option("tree", args->tree, "Baked tree directory (holds manifest.json)")->required();
  command->add_option("-o,--output", args->output, "PNG file to write (atomically)")->required();
  command->add_option("--camera", args->camera,
                      "eye_x,eye_y,eye_z,target_x,target_y,target_z in the tree's frame (model units relative to its "
                      "manifest's origin; default: frame the whole model)");
  CLI::Option* fov =
      command->add_option("--fov", args->fov_degrees, "Vertical field of view in degrees")->capture_default_str();
  command
      ->add_flag("--ortho", args->ortho,
                 "Orthographic view (a top-down or editor camera: the cut does not coarsen with distance), "
                 "as high as the model's bounding sphere")
      ->excludes(fov);
  command->add_option("--width", args->width, "Picture width in pixels")->capture_default_str();
  command->add_option("--height", args->height, "Picture height in pixels (the SSE viewport)")->capture_default_str();
  command->add_option("--sse", args->sse, "Screen-space error target in pixels of the picture's height")
      ->capture_default_str()
      ->check(positive_finite());
  command->add_option("--budget", args->budget, "Cache budget: 8M, 512K, 1G")->capture_default_str();
  command->add_flag("--cull-back-faces", args->cull_back_faces,
                    "Do not draw triangles facing away from the camera, as a game does (default: both sides, lit)");
  CLI::Option* texture = command->add_flag(
      "--texture", args->texture,
      "Draw the tree's texture (the image its input's PLY named; PNG or JPEG) on the nodes instead of "
      "tinting them by detail level");
  command
      ->add_flag("--colors", args->colors,
                 "Draw the nodes in their own colours (the input's, per vertex or per face), lit, instead of tinting "
                 "them by detail level")
      ->excludes(texture);
  command->callback([args, &context] { context.exit_code = run_render(*args, context); });
}

void add_sample_command(CLI::App& app, CommandContext& context) {
  auto args = std::make_shared<SampleArgs>();
  CLI::App* command = app.add_subcommand(
      "sample", "Write a deterministic procedural mesh (streaming, bounded memory for any size)");
  command->add_option("--shape", args->shape, "rock | terrain | city | tube")->required();
  command
      ->add_option("--triangles", args->triangles,
                   "About this many triangles: 200000, 2e5, 200K, 20M")
      ->required();
  command
      ->add_option("--attributes", args->attributes,
                   "Comma-separated subset of normal,color,uv; 'none' for positions only")
      ->capture_default_str();
  command->add_option("--seed", args->seed, "Noise seed; same seed, same bytes")
      ->capture_default_str();
  command
      ->add_option("--offset", args->offset,
                   "x,y,z added to every position, written as double (a geo-referenced model: 4e6,5e5,0)")
      ->delimiter(',')
      ->expected(3);
  command->add_flag("--ascii", args->ascii, "Write ascii PLY (default: binary little-endian)");
  command->add_flag("--texture", args->texture,
                    "Also write a texture for the UVs next to the PLY (OUT.png: hue bands along u, a checker), named "
                    "in its header as textured scans name theirs (comment TextureFile)");
  command->add_option("-o,--output", args->output, "Output .ply file")->required();
  command->callback([args, &context] { context.exit_code = run_sample(*args, context); });
}

void add_walk_command(CLI::App& app, CommandContext& context) {
  auto args = std::make_shared<WalkArgs>();
  CLI::App* command = app.add_subcommand(
      "walk", "Replay a camera path against a baked tree with the streaming runtime; paging statistics");
  command->add_option("tree", args->tree, "Baked tree directory (holds manifest.json)")->required();
  command
      ->add_option("--path", args->path,
                   "orbit | far-to-near | flythrough | FILE.json ({\"keyframes\": [{\"eye\": [x,y,z], "
                   "\"target\": [x,y,z]}, ...]}, model units)")
      ->capture_default_str();
  command->add_option("--frames", args->frames, "Frames to replay, 1..1000000 (each keeps a line of statistics)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1'000'000u));
  command->add_option("--budget", args->budget, "Cache budget: 8M, 512K, 1G")->capture_default_str();
  command->add_option("--sse", args->sse, "Screen-space error target in pixels (1080 px viewport)")
      ->capture_default_str()
      ->check(positive_finite());
  command->add_option("--fps", args->fps,
                      "Frame rate of the replay, 1..1000; 0 = as fast as possible (the selection's cost: loads then "
                      "rarely finish in time, and frames draw mostly fallbacks)")
      ->capture_default_str()
      ->check(number_check([](double fps) { return fps == 0.0 || (fps >= 1.0 && fps <= 1000.0); },
                           "must be 0 or within 1..1000", "0 or 1..1000"));
  command->add_option("--threads", args->threads, "Loader threads, 1..1024")
      ->capture_default_str()
      ->check(CLI::Range(1u, kMaxThreads));
  command->add_option("--loads-in-flight", args->loads_in_flight, "Loads queued or running at once, 1..4096")
      ->capture_default_str()
      ->check(CLI::Range(1u, 4096u));
  command->add_flag("--no-prefetch", args->no_prefetch, "Load only what frames want");
  command->add_option("--csv", args->csv, "Write per-frame statistics to this CSV file");
  command->add_option("--plot", args->plot, "Write per-frame charts to this PNG file");
  command->add_option("--frames-png", args->frames_png,
                      "Render selected frames (960x540, nodes tinted by detail level) into DIR/frame_NNNNNN.png");
  command->add_option("--frames-png-every", args->frames_png_every, "With --frames-png: every K-th frame, from frame 0")
      ->capture_default_str();
  command->callback([args, &context] { context.exit_code = run_walk(*args, context); });
}

}  // namespace

void add_commands(CLI::App& app, CommandContext& context) {
  // --help lists them in the order of a user's work: make an input, bake it, look at the tree,
  // stream it, take cuts out of it, measure them.
  add_sample_command(app, context);
  add_bake_command(app, context);
  add_info_command(app, context);
  add_render_command(app, context);
  add_walk_command(app, context);
  add_extract_command(app, context);
  add_export_command(app, context);
  add_eval_command(app, context);
  add_reference_command(app, context);
  add_compare_command(app, context);
}

}  // namespace octolod::cli
