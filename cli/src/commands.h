// The subcommands' arguments, as parsed from the command line (command_line.cpp declares the
// options, with their help text and checks), and the functions that run them (cmd_<name>.cpp).
// Each run_<name> returns the process exit code: 0, or the ErrorCode of what failed (reported on
// stderr); with context.json it prints one JSON document on stdout.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "command.h"
#include "cut_choice.h"
#include "octolod/formats/gltf.h"
#include "octolod/runtime/streaming_tree.h"

namespace octolod::cli {

struct BakeArgs {
  std::string input;
  std::string output;
  std::uint32_t max_tris = 2000;
  std::uint32_t max_depth = 10;
  std::string memory = "64M";
  std::string work_dir;
  unsigned threads = 0;
  bool out_of_core = false;
  std::string method = "grid";
  double lod_ratio = 0.5;
};

struct CompareArgs {
  std::string input;
  std::string tree;
  std::vector<double> errors;
  std::vector<double> fractions{0.3, 0.1, 0.03, 0.01};
  std::uint64_t samples = 0;
  bool markdown = false;
  bool no_reference = false;
  std::string pictures;       // directory for the error pictures; empty: none
  double picture_scale = 0.0;  // top of their colour scale, model units; 0: each picture's largest
};

struct EvalArgs {
  std::string a;
  std::string b;
  std::uint64_t samples = 0;
  std::uint64_t seed = 1;
  unsigned threads = 0;
  std::string picture;         // PNG path for the error picture; empty: none
  double picture_scale = 0.0;  // top of its colour scale, model units; 0: its largest distance
};

struct ExportArgs {
  std::string tree;
  CutChoice cut;
  std::string output;
  bool draco = false;
  DracoOptions draco_options;
};

struct ExtractArgs {
  std::string tree;
  CutChoice cut;
  std::string output;
  bool ascii = false;
};

struct ReferenceArgs {
  std::string input;
  std::uint32_t triangles = 0;
  std::string output;
  bool ascii = false;
};

struct RenderArgs {
  std::string tree;
  std::string camera;  // "ex,ey,ez,tx,ty,tz", empty: framing_camera
  double fov_degrees = 60.0;
  bool ortho = false;  // an orthographic view framing the model sphere instead of --fov's perspective
  bool cull_back_faces = false;  // as a game draws: a triangle facing away from the camera is not drawn
  bool texture = false;  // the tree's texture on the nodes instead of their detail-level tints
  bool colors = false;   // the nodes' own colours (the input's, per vertex or face) instead of tints
  int width = 1024;
  int height = 768;
  // The runtime's default (walk's too): the framed demo rock (samples/rock_small.ply, 40K
  // triangles) is drawn from two detail levels at 2 px (13.9K triangles), from the root's one
  // LOD alone at 4 px.
  double sse = 2.0;
  std::string budget = "512M";
  std::string output;
};

struct SampleArgs {
  std::string shape;
  std::string triangles;
  std::string attributes = "normal,color,uv";
  std::uint64_t seed = 1;
  std::vector<double> offset;  // empty or x, y, z
  bool ascii = false;
  bool texture = false;  // also write a procedural texture next to the PLY, named in its header
  std::string output;
};

struct WalkArgs {
  std::string tree;
  std::string path = "orbit";
  std::uint32_t frames = 600;
  std::string budget = "64M";
  double sse = 2.0;
  double fps = 60.0;
  unsigned threads = 2;
  std::uint32_t loads_in_flight = runtime::StreamingOptions{}.max_loads_in_flight;
  bool no_prefetch = false;
  std::string csv;
  std::string plot;
  std::string frames_png;
  std::uint32_t frames_png_every = 100;
};

int run_bake(const BakeArgs& args, const CommandContext& context);
int run_compare(const CompareArgs& args, const CommandContext& context);
int run_eval(const EvalArgs& args, const CommandContext& context);
int run_export(const ExportArgs& args, const CommandContext& context);
int run_extract(const ExtractArgs& args, const CommandContext& context);
// `path`: a baked tree's directory, or a PLY file (run_ply_info).
int run_info(const std::string& path, const CommandContext& context);
int run_ply_info(const std::string& ply, const CommandContext& context);
int run_reference(const ReferenceArgs& args, const CommandContext& context);
int run_render(const RenderArgs& args, const CommandContext& context);
int run_sample(const SampleArgs& args, const CommandContext& context);
int run_walk(const WalkArgs& args, const CommandContext& context);

}  // namespace octolod::cli
