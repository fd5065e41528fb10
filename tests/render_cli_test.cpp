// render_cli_tests: `octolod render` and `octolod walk --frames-png` write pictures of the cut the
// streaming runtime selects, with every node tinted by its detail level; `compare --pictures`
// and `eval --picture` colour meshes by their distance to each other. Runs the CLI built next to
// the tests (OCTOLOD_CLI) on the synthetic tree of runtime_test_helpers.h written to disk, and on
// a tree the CLI bakes from a generated rock.
#include <gtest/gtest.h>

#include <png.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "image.h"
#include "offscreen_renderer.h"
#include "runtime_test_helpers.h"

namespace octolod::cli {
namespace {

constexpr std::uint32_t kBackground = 0x20242c;  // RenderView's default

struct Picture {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;
  std::uint32_t get(int x, int y) const {
    const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 3;
    return (std::uint32_t{rgb[i]} << 16) | (std::uint32_t{rgb[i + 1]} << 8) | rgb[i + 2];
  }
};

Picture read_png(const std::filesystem::path& path) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  Picture picture;
  if (!png_image_begin_read_from_file(&image, path.c_str())) {
    ADD_FAILURE() << path << ": " << image.message;
    return picture;
  }
  image.format = PNG_FORMAT_RGB;
  picture.width = static_cast<int>(image.width);
  picture.height = static_cast<int>(image.height);
  picture.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, picture.rgb.data(), 0, nullptr)) {
    ADD_FAILURE() << path << ": " << image.message;
    picture = {};
  }
  return picture;
}

// Hue in degrees [0, 360) of an RGB colour; lighting scales all three channels alike, so a shaded
// pixel keeps the hue of its material (up to rounding and clamping of bright pixels).
double hue_degrees(double r, double g, double b) {
  const double hi = std::max({r, g, b}), lo = std::min({r, g, b}), span = hi - lo;
  if (span <= 0) return 0;
  double h = 0;
  if (hi == r) h = std::fmod((g - b) / span, 6.0);
  else if (hi == g) h = (b - r) / span + 2.0;
  else h = (r - g) / span + 4.0;
  h *= 60.0;
  return h < 0 ? h + 360.0 : h;
}

// Hues of the picture's non-background pixels, row by row.
std::vector<double> lit_hues(const Picture& picture) {
  std::vector<double> hues;
  for (int y = 0; y < picture.height; ++y)
    for (int x = 0; x < picture.width; ++x) {
      const std::uint32_t p = picture.get(x, y);
      if (p != kBackground) hues.push_back(hue_degrees((p >> 16) & 0xFF, (p >> 8) & 0xFF, p & 0xFF));
    }
  return hues;
}

double hue_distance(double a, double b) {
  const double d = std::abs(a - b);
  return std::min(d, 360.0 - d);
}

// The material of a mesh without colours tinted for `level`: half grey 0.8, half tint
// (offscreen_renderer's mix), as a hue.
double level_hue(std::uint32_t level) {
  const glm::vec3 c = 0.5f * glm::vec3(0.8f) + 0.5f * lod_tint(level);
  return hue_degrees(c.r, c.g, c.b);
}

// Hues of the lit pixels of an error picture's panel (800 x 600 each, `column` and `row` from
// the top left), below its caption.
std::vector<double> panel_hues(const Picture& picture, int column, int row) {
  std::vector<double> hues;
  for (int y = 600 * row + 40; y < 600 * (row + 1); ++y)
    for (int x = 800 * column; x < 800 * (column + 1); ++x) {
      const std::uint32_t p = picture.get(x, y);
      if (p != kBackground) hues.push_back(hue_degrees((p >> 16) & 0xFF, (p >> 8) & 0xFF, p & 0xFF));
    }
  return hues;
}

std::size_t count_below(const std::vector<double>& hues, double hue) {
  return static_cast<std::size_t>(std::count_if(hues.begin(), hues.end(), [&](double h) { return h < hue; }));
}

std::string file_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::filesystem::path scratch_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("octolod_render_cli_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

struct CliRun {
  int exit_code = -1;
  nlohmann::json json;
};

// Runs `octolod <arguments>` with stdout captured; parses it as JSON when it is one.
CliRun octolod(const std::string& arguments, const std::filesystem::path& dir) {
  const auto out = dir / "stdout.txt";
  const std::string command = std::string(std::getenv("OCTOLOD_CLI")) + " " + arguments + " > " + out.string() +
                              " 2> " + (dir / "stderr.txt").string();
  CliRun run;
  const int status = std::system(command.c_str());
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(out);
  run.json = nlohmann::json::parse(in, nullptr, false);
  return run;
}

// A 20K-triangle rock (`seed`) sampled into dir/rock.ply and baked into dir/rock at 64M.
bool bake_rock(const std::filesystem::path& dir, int seed = 1) {
  const std::string ply = (dir / "rock.ply").string();
  return octolod("sample --shape rock --triangles 20000 --seed " + std::to_string(seed) + " -o " + ply, dir).exit_code == 0 &&
         octolod("bake " + ply + " -o " + (dir / "rock").string() + " --memory 64M", dir).exit_code == 0;
}

class RenderCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* cli = std::getenv("OCTOLOD_CLI");
    if (cli == nullptr || !std::filesystem::exists(cli)) GTEST_SKIP() << "OCTOLOD_CLI not built";
  }
};

TEST_F(RenderCli, SyntheticTreeShowsOneTintPerDetailLevelAndNoOther) {
  // The 3-level synthetic tree ([0,64]^3, 2 LODs per node, no vertex colours) seen by the default
  // camera at 500 px with a 2 px target: near leaves draw their original triangles (level 0), farther nodes coarser
  // LODs, so the settled cut spans several detail levels.
  const auto dir = scratch_dir("synthetic");
  const runtime::testing::SyntheticTree tree = runtime::testing::make_full_octree(3);
  runtime::testing::write_tree(tree, dir / "tree");
  const auto png = dir / "frame.png";
  const CliRun run = octolod("--json render " + (dir / "tree").string() + " --width 640 --height 500 --sse 2 -o " + png.string(), dir);
  ASSERT_EQ(run.exit_code, 0);
  ASSERT_TRUE(run.json.is_object());
  EXPECT_TRUE(run.json.at("complete").get<bool>());
  EXPECT_EQ(run.json.at("fallbacks"), 0);

  // the histogram accounts for every drawn node and triangle
  std::set<std::uint32_t> levels;
  std::uint64_t nodes = 0, triangles = 0;
  for (const nlohmann::json& level : run.json.at("lod_histogram")) {
    levels.insert(level.at("level").get<std::uint32_t>());
    nodes += level.at("nodes").get<std::uint64_t>();
    triangles += level.at("triangles").get<std::uint64_t>();
  }
  EXPECT_EQ(nodes, run.json.at("nodes_drawn").get<std::uint64_t>());
  EXPECT_EQ(triangles, run.json.at("triangles").get<std::uint64_t>());
  ASSERT_GE(levels.size(), 2u) << run.json.dump();

  // every lit pixel has the hue of a level in the histogram; at least two levels are visible
  const Picture picture = read_png(png);
  ASSERT_EQ(picture.width, 640);
  ASSERT_EQ(picture.height, 500);
  std::map<std::uint32_t, int> pixels_per_level;
  const std::vector<double> hues = lit_hues(picture);
  const int lit = static_cast<int>(hues.size());
  int unexplained = 0;
  for (const double hue : hues) {
    std::uint32_t best = 0;
    double best_distance = 1e9;
    for (std::uint32_t level = 0; level < 8; ++level)
      if (hue_distance(hue, level_hue(level)) < best_distance) {
        best_distance = hue_distance(hue, level_hue(level));
        best = level;
      }
    if (best_distance > 10.0 || levels.count(best) == 0) ++unexplained;
    else ++pixels_per_level[best];
  }
  EXPECT_GT(lit, 1000);
  EXPECT_LT(unexplained, lit / 100) << "pixels whose hue is no drawn level's tint";
  int visible_levels = 0;
  std::string seen;
  for (const auto& [level, count] : pixels_per_level) {
    visible_levels += count >= 50 ? 1 : 0;
    seen += " level " + std::to_string(level) + ": " + std::to_string(count) + " px;";
  }
  EXPECT_GE(visible_levels, 2) << seen << " of " << lit << " lit, " << unexplained << " unexplained";
  std::filesystem::remove_all(dir);
}

TEST_F(RenderCli, BakedRockIsDrawnAndEveryDrawnTriangleIsCounted) {
  const auto dir = scratch_dir("rock");
  ASSERT_TRUE(bake_rock(dir));
  const auto png = dir / "rock.png";
  const CliRun run = octolod("--json render " + (dir / "rock").string() + " --width 320 --height 240 -o " + png.string(), dir);
  ASSERT_EQ(run.exit_code, 0);
  EXPECT_TRUE(run.json.at("complete").get<bool>());
  EXPECT_EQ(run.json.at("fallbacks"), 0);
  EXPECT_GT(run.json.at("triangles").get<std::uint64_t>(), 0u);

  // The default camera frames the whole rock: it covers a good part of the picture, and none of
  // it touches the border (nothing clipped).
  const Picture picture = read_png(png);
  ASSERT_EQ(picture.width, 320);
  int lit = 0, border = 0;
  for (int y = 0; y < picture.height; ++y)
    for (int x = 0; x < picture.width; ++x) {
      if (picture.get(x, y) == kBackground) continue;
      ++lit;
      border += (x == 0 || y == 0 || x == picture.width - 1 || y == picture.height - 1) ? 1 : 0;
    }
  EXPECT_GT(lit, picture.width * picture.height / 10);
  EXPECT_EQ(border, 0);
  std::filesystem::remove_all(dir);
}

// render --texture draws the tree's texture instead of the detail tints: a rock whose PLY names a
// texture red where u < 1/6 and blue beyond (the framed side shows u from about 0.8 round to
// 0.35) shows only those two hues, and both. A tree without a
// texture is a usage error, with no picture.
TEST_F(RenderCli, TextureFlagDrawsTheTreesTextureInsteadOfTheTints) {
  const auto dir = scratch_dir("texture");
  // sample --texture writes rock.png next to rock.ply and names it in the header
  const std::string ply = (dir / "rock.ply").string();
  const CliRun sampled = octolod("--json sample --shape rock --triangles 20000 --texture -o " + ply, dir);
  ASSERT_EQ(sampled.exit_code, 0);
  EXPECT_EQ(sampled.json.at("texture"), (dir / "rock.png").string());
  ASSERT_EQ(read_png(dir / "rock.png").width, 1024);
  EXPECT_EQ(octolod("sample --shape rock --triangles 20000 --attributes normal --texture -o " +
                        (dir / "bare.ply").string(), dir).exit_code, 1);
  EXPECT_FALSE(std::filesystem::exists(dir / "bare.ply"));
  // ... replaced here by one whose hues the test knows
  Image halves(60, 32, 0x0000ff);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 10; ++x) halves.set(x, y, 0xff0000);
  ASSERT_TRUE(write_png(dir / "rock.png", halves).ok());
  ASSERT_EQ(octolod("bake " + ply + " -o " + (dir / "rock").string(), dir).exit_code, 0);

  const auto png = dir / "textured.png";
  const CliRun run =
      octolod("--json render " + (dir / "rock").string() + " --texture --width 320 --height 240 -o " + png.string(), dir);
  ASSERT_EQ(run.exit_code, 0);
  EXPECT_TRUE(run.json.at("texture").get<bool>());
  // red, blue, their blends where the texels meet (magenta, 255-345 degrees), nothing between
  // red and blue the other way round (the tints' and the rock's colours: brown, yellow, green)
  int red = 0, blue = 0, lit = 0, unlike_the_texture = 0;
  for (double hue : lit_hues(read_png(png))) {
    ++lit;
    if (hue < 15 || hue > 345) ++red;
    else if (std::abs(hue - 240) < 15) ++blue;
    else if (hue < 225) ++unlike_the_texture;
  }
  EXPECT_GT(red, 1000);
  EXPECT_GT(blue, 1000);
  EXPECT_LT(unlike_the_texture, lit / 100);

  std::filesystem::remove(dir / "rock.png");  // the bake warns and the tree has no texture
  ASSERT_EQ(octolod("bake " + ply + " -o " + (dir / "plain").string(), dir).exit_code, 0);
  const auto refused = dir / "refused.png";
  EXPECT_EQ(octolod("render " + (dir / "plain").string() + " --texture -o " + refused.string(), dir).exit_code, 1);
  EXPECT_FALSE(std::filesystem::exists(refused));
  std::filesystem::remove_all(dir);
}

// render --colors draws the nodes in their own colours instead of the detail tints: a rock
// whose PLY gives its first half of faces red and the rest blue (colours per face, no vertex
// colours) shows only those hues and their blends, the tinted picture others as well. A tree
// without colours is a usage error, with no picture.
TEST_F(RenderCli, ColorsFlagDrawsTheInputsColoursInsteadOfTheTints) {
  const auto dir = scratch_dir("colors");
  const auto plain = dir / "plain.ply";
  ASSERT_EQ(octolod("sample --shape rock --triangles 20000 --attributes normal --ascii -o " + plain.string(), dir).exit_code,
            0);
  std::ifstream in(plain);
  std::string text, line;
  std::size_t faces = 0, face = 0, vertices_left = 0;
  bool body = false;
  while (std::getline(in, line)) {
    if (!body) {
      if (line.rfind("element vertex ", 0) == 0) vertices_left = std::stoul(line.substr(15));
      if (line.rfind("element face ", 0) == 0) faces = std::stoul(line.substr(13));
      body = line == "end_header";
      text += line + "\n";
      if (line.rfind("property list", 0) == 0) text += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
      continue;
    }
    if (vertices_left > 0) {
      --vertices_left;
      text += line + "\n";
      continue;
    }
    text += line + (face++ < faces / 2 ? " 255 0 0\n" : " 0 0 255\n");
  }
  ASSERT_EQ(face, faces);
  std::ofstream(dir / "coloured.ply") << text;
  ASSERT_EQ(octolod("bake " + (dir / "coloured.ply").string() + " -o " + (dir / "rock").string(), dir).exit_code, 0);

  const std::string render = "--json render " + (dir / "rock").string() + " --width 320 --height 240 -o ";
  const CliRun run = octolod(render + (dir / "colours.png").string() + " --colors", dir);
  ASSERT_EQ(run.exit_code, 0);
  EXPECT_TRUE(run.json.at("colors").get<bool>());
  ASSERT_EQ(octolod(render + (dir / "tinted.png").string(), dir).exit_code, 0);
  // red, blue, and magenta where they blend (255-345 degrees); the tints' hues are between
  const auto count_unlike = [](const Picture& picture, int& red, int& blue) {
    int lit = 0, unlike = 0;
    for (double hue : lit_hues(picture)) {
      ++lit;
      if (hue < 15 || hue > 345) ++red;
      else if (std::abs(hue - 240) < 15) ++blue;
      else if (hue < 225) ++unlike;
    }
    EXPECT_GT(lit, 320 * 240 / 10);
    return unlike;
  };
  int red = 0, blue = 0;
  const int unlike_own = count_unlike(read_png(dir / "colours.png"), red, blue);
  EXPECT_GT(red, 1000);
  EXPECT_GT(blue, 1000);
  EXPECT_EQ(unlike_own, 0);
  // the same cut tinted: hues moved towards the tints'
  const std::vector<double> own = lit_hues(read_png(dir / "colours.png"));
  const std::vector<double> tinted = lit_hues(read_png(dir / "tinted.png"));
  ASSERT_EQ(own.size(), tinted.size());
  int moved = 0;
  for (std::size_t i = 0; i < own.size(); ++i) moved += std::abs(own[i] - tinted[i]) > 10;
  EXPECT_GT(moved, 1000);

  ASSERT_EQ(octolod("bake " + plain.string() + " -o " + (dir / "uncoloured").string(), dir).exit_code, 0);
  const auto refused = dir / "refused.png";
  EXPECT_EQ(octolod("render " + (dir / "uncoloured").string() + " --colors -o " + refused.string(), dir).exit_code, 1);
  EXPECT_FALSE(std::filesystem::exists(refused));
  EXPECT_EQ(octolod("render " + (dir / "rock").string() + " --colors --texture -o " + refused.string(), dir).exit_code,
            1);
  std::filesystem::remove_all(dir);
}

TEST_F(RenderCli, CullingBackFacesOpensNoTriangleSizedHole) {
  // Drawn as a game draws it, back faces culled, a closed rock's cut shows the background only
  // where the nearest surface faces away. The framed cut of this rock (seed 2) had a triangle
  // inside out among its neighbours there, 13 pixels of background at 320 x 240; what is left
  // are 1-pixel lines where a simplified fold crosses itself (2 pixels).
  const auto dir = scratch_dir("culled");
  ASSERT_TRUE(bake_rock(dir, 2));
  const std::string render = "render " + (dir / "rock").string() + " --width 320 --height 240 -o ";
  ASSERT_EQ(octolod(render + (dir / "both.png").string(), dir).exit_code, 0);
  ASSERT_EQ(octolod(render + (dir / "culled.png").string() + " --cull-back-faces", dir).exit_code, 0);
  const Picture both = read_png(dir / "both.png"), culled = read_png(dir / "culled.png");
  int lit = 0, holes = 0;
  for (int y = 0; y < both.height; ++y)
    for (int x = 0; x < both.width; ++x) {
      if (both.get(x, y) == kBackground) continue;
      ++lit;
      holes += culled.get(x, y) == kBackground;
    }
  EXPECT_GT(lit, both.width * both.height / 10);
  EXPECT_LE(holes, 4);
  std::filesystem::remove_all(dir);
}

TEST_F(RenderCli, DemoPictureShowsAtLeastTwoDetailTints) {
  // What scripts/demo does: bake the bundled rock, render it with every default (camera framing
  // the model, --sse). The picture must show the cut's LOD structure: pixels of at least two
  // detail levels' tints. The rock has vertex colours (half of each pixel's material), so a pixel
  // is attributed to the drawn level whose tint hue is nearest to its own.
  const auto dir = scratch_dir("demo");
  const auto ply = std::filesystem::path(__FILE__).parent_path().parent_path() / "samples" / "rock_small.ply";
  ASSERT_TRUE(std::filesystem::exists(ply)) << ply;
  ASSERT_EQ(octolod("bake " + ply.string() + " -o " + (dir / "rock").string() + " --memory 64M", dir).exit_code, 0);
  const auto png = dir / "rock.png";
  const CliRun run = octolod("--json render " + (dir / "rock").string() + " -o " + png.string(), dir);
  ASSERT_EQ(run.exit_code, 0);
  ASSERT_TRUE(run.json.is_object());
  std::vector<std::uint32_t> levels;
  for (const nlohmann::json& level : run.json.at("lod_histogram")) levels.push_back(level.at("level").get<std::uint32_t>());
  ASSERT_GE(levels.size(), 2u) << "the default cut is one detail level: " << run.json.dump();

  const Picture picture = read_png(png);
  std::map<std::uint32_t, int> pixels_per_level;
  const std::vector<double> hues = lit_hues(picture);
  const int lit = static_cast<int>(hues.size());
  for (const double hue : hues) {
    const auto nearest = std::min_element(levels.begin(), levels.end(), [&](std::uint32_t a, std::uint32_t b) {
      return hue_distance(hue, level_hue(a)) < hue_distance(hue, level_hue(b));
    });
    ++pixels_per_level[*nearest];
  }
  EXPECT_GT(lit, picture.width * picture.height / 10);
  int visible = 0;
  std::string seen;
  for (const auto& [level, count] : pixels_per_level) {
    visible += count >= lit / 50 ? 1 : 0;  // at least 2% of the rock
    seen += " level " + std::to_string(level) + ": " + std::to_string(count) + " px;";
  }
  EXPECT_GE(visible, 2) << seen << " of " << lit << " lit";
  std::filesystem::remove_all(dir);
}

// `compare --pictures`: one PNG per cut, 800 x 600 pixels per panel and a 48-pixel scale strip:
// the cut coloured by its distance to the input, and the input by its distance to the cut; with
// the reference, a second row (the reference to the input, the input to the reference). The
// finest cut is the input's own triangles: every pixel of both panels blue (hue near 240). A
// coarse cut and its reference show warmer hues in all four panels, and their scale is far
// above the finest cut's.
TEST_F(RenderCli, ComparePicturesColourTheCutsAndTheInputByTheirDistances) {
  const auto dir = scratch_dir("compare");
  const auto ply = dir / "rock.ply";
  ASSERT_TRUE(bake_rock(dir));

  const CliRun finest = octolod("--json compare " + ply.string() + " " + (dir / "rock").string() +
                                    " --errors 0 --no-reference --pictures " + (dir / "finest").string(),
                                dir);
  ASSERT_EQ(finest.exit_code, 0);
  const nlohmann::json& row = finest.json.at("rows").at(0);
  EXPECT_EQ(row.at("triangles"), 20000);
  const Picture one = read_png(row.at("picture").get<std::string>());
  EXPECT_EQ(one.width, 1600);
  EXPECT_EQ(one.height, 648);
  for (int column = 0; column < 2; ++column) {
    const std::vector<double> hues = panel_hues(one, column, 0);
    EXPECT_GT(hues.size(), 800u * 600u / 20) << column;
    EXPECT_EQ(count_below(hues, 200.0), 0u) << column;
  }
  const double diagonal = finest.json.at("diagonal").get<double>();
  EXPECT_LT(row.at("picture_scale").get<double>(), 1e-4 * diagonal);

  const CliRun coarse = octolod("--json compare " + ply.string() + " " + (dir / "rock").string() +
                                    " --fractions 0.02 --pictures " + (dir / "coarse").string(),
                                dir);
  ASSERT_EQ(coarse.exit_code, 0);
  const nlohmann::json& coarse_row = coarse.json.at("rows").at(0);
  EXPECT_GT(coarse_row.at("picture_scale").get<double>(), 1e-3 * diagonal);
  const Picture four = read_png(coarse_row.at("picture").get<std::string>());
  EXPECT_EQ(four.width, 1600);
  EXPECT_EQ(four.height, 1248);
  for (int panel = 0; panel < 4; ++panel) {
    const std::vector<double> hues = panel_hues(four, panel % 2, panel / 2);
    EXPECT_GT(hues.size(), 800u * 600u / 20) << panel;
    EXPECT_GT(count_below(hues, 180.0), 0u) << panel;
  }

  // a pictures directory that cannot be made is an I/O error (exit 4) before any measuring
  std::ofstream(dir / "a-file") << "x";
  const CliRun blocked = octolod("compare " + ply.string() + " " + (dir / "rock").string() + " --pictures " +
                                     (dir / "a-file").string(),
                                 dir);
  EXPECT_EQ(blocked.exit_code, 4);
  const std::string message = file_text(dir / "stderr.txt");
  EXPECT_NE(message.find("a-file: cannot create the pictures' directory"), std::string::npos) << message;
  std::filesystem::remove_all(dir);
}

// `eval --picture`: B coloured by its distance to A next to A by its distance to B. A mesh
// against itself is blue throughout; against a coarse reference both panels show warmer hues,
// unless --picture-scale puts the red end far above every distance.
TEST_F(RenderCli, EvalPictureColoursEachMeshByItsDistanceToTheOther) {
  const auto dir = scratch_dir("eval");
  const auto ply = dir / "rock.ply", coarse = dir / "coarse.ply";
  ASSERT_EQ(octolod("sample --shape rock --triangles 20000 -o " + ply.string(), dir).exit_code, 0);
  ASSERT_EQ(octolod("reference " + ply.string() + " --triangles 400 -o " + coarse.string(), dir).exit_code, 0);
  const CliRun same = octolod("--json eval " + ply.string() + " " + ply.string() + " --picture " +
                                  (dir / "same.png").string(),
                              dir);
  ASSERT_EQ(same.exit_code, 0);
  EXPECT_LT(same.json.at("picture").at("scale").get<double>(), 1e-4 * same.json.at("diagonal").get<double>());
  const Picture blue = read_png(dir / "same.png");
  ASSERT_EQ(blue.width, 1600);
  ASSERT_EQ(blue.height, 648);
  const CliRun apart = octolod("--json eval " + ply.string() + " " + coarse.string() + " --picture " +
                                   (dir / "apart.png").string(),
                               dir);
  ASSERT_EQ(apart.exit_code, 0);
  const Picture warm = read_png(dir / "apart.png");
  for (int column = 0; column < 2; ++column) {
    const std::vector<double> same_hues = panel_hues(blue, column, 0), apart_hues = panel_hues(warm, column, 0);
    EXPECT_GT(same_hues.size(), 800u * 600u / 20) << column;
    EXPECT_EQ(count_below(same_hues, 200.0), 0u) << column;
    EXPECT_GT(count_below(apart_hues, 180.0), 0u) << column;
  }
  // a given scale is the picture's: far above every distance, everything is blue
  const double diagonal = apart.json.at("diagonal").get<double>();
  const CliRun fixed = octolod("--json eval " + ply.string() + " " + coarse.string() + " --picture " +
                                   (dir / "fixed.png").string() + " --picture-scale " + std::to_string(10 * diagonal),
                               dir);
  ASSERT_EQ(fixed.exit_code, 0);
  EXPECT_NEAR(fixed.json.at("picture").at("scale").get<double>(), 10 * diagonal, 1e-6 * diagonal);
  const Picture cold = read_png(dir / "fixed.png");
  for (int column = 0; column < 2; ++column) EXPECT_EQ(count_below(panel_hues(cold, column, 0), 200.0), 0u) << column;
  EXPECT_EQ(octolod("eval " + ply.string() + " " + coarse.string() + " --picture " + (dir / "x.png").string() +
                        " --picture-scale 0",
                    dir)
                .exit_code,
            1);
  // nowhere to write it: an I/O error before the measuring
  const CliRun nowhere = octolod("eval " + ply.string() + " " + coarse.string() + " --picture " +
                                     (dir / "missing" / "x.png").string(),
                                 dir);
  EXPECT_EQ(nowhere.exit_code, 4);
  EXPECT_NE(file_text(dir / "stderr.txt").find("does not exist"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_F(RenderCli, MalformedCameraIsAUsageErrorAndWritesNothing) {
  const auto dir = scratch_dir("usage");
  runtime::testing::write_tree(runtime::testing::make_full_octree(2), dir / "tree");
  const auto png = dir / "frame.png";
  for (const char* camera : {"1,2,3", "1,2,3,4,5,x", "1,1,1,1,1,1"}) {
    EXPECT_EQ(octolod("render " + (dir / "tree").string() + " --camera " + camera + " -o " + png.string(), dir).exit_code, 1)
        << camera;
    EXPECT_FALSE(std::filesystem::exists(png)) << camera;
  }
  EXPECT_EQ(octolod("render " + (dir / "missing").string() + " -o " + png.string(), dir).exit_code, 4);
  EXPECT_FALSE(std::filesystem::exists(png));
  std::filesystem::remove_all(dir);
}

// Pictures are published by renaming over their path: a FIFO (or a device) there is refused
// and kept, not replaced by a regular file.
TEST_F(RenderCli, AnOutputThatIsNotARegularFileIsRefusedAndKept) {
  const auto dir = scratch_dir("fifo");
  runtime::testing::write_tree(runtime::testing::make_full_octree(2), dir / "tree");
  const auto fifo = dir / "frame.png";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(octolod("render " + (dir / "tree").string() + " -o " + fifo.string(), dir).exit_code, 4);
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  const std::string errors = file_text(dir / "stderr.txt");
  EXPECT_NE(errors.find("frame.png: cannot write the PNG: it is not a regular file"), std::string::npos) << errors;
  std::filesystem::remove_all(dir);
}

// Flips the middle byte of every node file of the tree at `tree`; returns how many there were.
std::size_t damage_node_files(const std::filesystem::path& tree) {
  std::size_t damaged = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(tree)) {
    if (!entry.is_regular_file() || entry.path().filename() == "manifest.json") continue;
    const auto middle = static_cast<std::streamoff>(std::filesystem::file_size(entry.path()) / 2);
    std::fstream file(entry.path(), std::ios::in | std::ios::out | std::ios::binary);
    file.seekg(middle);
    const char byte = static_cast<char>(file.get() ^ 0x5A);
    file.seekp(middle);
    file.put(byte);
    ++damaged;
  }
  return damaged;
}

// A node file that fails to load (here: every one, its middle byte flipped) fails the
// command naming the file, and no picture is written: a damaged tree is bad input, not a picture
// of fallbacks.
TEST_F(RenderCli, ANodeFileThatFailsToLoadIsBadInputAndWritesNothing) {
  const auto dir = scratch_dir("damaged");
  runtime::testing::write_tree(runtime::testing::make_full_octree(2), dir / "tree");
  ASSERT_GT(damage_node_files(dir / "tree"), 0u);
  const auto png = dir / "frame.png";
  EXPECT_EQ(octolod("render " + (dir / "tree").string() + " -o " + png.string(), dir).exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(png));
  const std::string errors = file_text(dir / "stderr.txt");
  EXPECT_NE(errors.find("lod0.bin"), std::string::npos) << errors;  // the root's, loaded first
  EXPECT_NE(errors.find("no picture written"), std::string::npos) << errors;
  std::filesystem::remove_all(dir);
}

TEST_F(RenderCli, ExplicitCameraLooksWhereItIsTold) {
  // Looking away from the tree shows only background; looking at it shows it.
  const auto dir = scratch_dir("camera");
  runtime::testing::write_tree(runtime::testing::make_full_octree(3), dir / "tree");
  const auto away = dir / "away.png", at = dir / "at.png";
  ASSERT_EQ(octolod("--json render " + (dir / "tree").string() + " --camera 32,32,200,32,32,400 --width 64 --height 64 -o " +
                        away.string(),
                    dir)
                .exit_code,
            0);
  const CliRun looked_at = octolod("--json render " + (dir / "tree").string() +
                                    " --camera 32,32,200,32,32,32 --width 64 --height 64 -o " + at.string(),
                                dir);
  ASSERT_EQ(looked_at.exit_code, 0);
  EXPECT_GT(looked_at.json.at("nodes_drawn").get<int>(), 0);
  auto lit_pixels = [](const Picture& p) {
    int lit = 0;
    for (int y = 0; y < p.height; ++y)
      for (int x = 0; x < p.width; ++x) lit += p.get(x, y) != kBackground ? 1 : 0;
    return lit;
  };
  EXPECT_EQ(lit_pixels(read_png(away)), 0);
  EXPECT_GT(lit_pixels(read_png(at)), 0);
  std::filesystem::remove_all(dir);
}

// --ortho: an orthographic view framing the model, whose cut is the same from near and far
// (the perspective one coarsens), drawn into a picture; it excludes --fov.
TEST_F(RenderCli, AnOrthographicViewDrawsTheSameCutFromAnyDistance) {
  const auto dir = scratch_dir("ortho");
  runtime::testing::write_tree(runtime::testing::make_full_octree(3), dir / "tree");
  const auto png = dir / "frame.png";
  auto render = [&](const std::string& options) {
    return octolod("--json render " + (dir / "tree").string() + " --width 1024 --height 1024 -o " + png.string() + " " +
                       options,
                   dir);
  };
  const CliRun near = render("--ortho --camera 32,32,150,32,32,32");
  const CliRun far = render("--ortho --camera 32,32,1500,32,32,32");
  ASSERT_EQ(near.exit_code, 0);
  ASSERT_EQ(far.exit_code, 0);
  EXPECT_TRUE(near.json.at("orthographic").get<bool>());
  EXPECT_TRUE(near.json.at("fov_degrees").is_null());
  EXPECT_GT(near.json.at("view_height").get<double>(), 0.0);  // model units: the framed sphere
  EXPECT_GT(near.json.at("nodes_drawn").get<int>(), 1);
  EXPECT_EQ(far.json.at("triangles"), near.json.at("triangles"));
  EXPECT_EQ(far.json.at("lod_histogram"), near.json.at("lod_histogram"));
  const CliRun perspective_far = render("--camera 32,32,1500,32,32,32");
  ASSERT_EQ(perspective_far.exit_code, 0);
  EXPECT_LT(perspective_far.json.at("triangles").get<int>(), far.json.at("triangles").get<int>());
  EXPECT_EQ(render("--ortho --fov 30").exit_code, 1);
  std::filesystem::remove_all(dir);
}

TEST_F(RenderCli, WalkFramesPngWritesEveryKthFrame) {
  const auto dir = scratch_dir("walk");
  runtime::testing::write_tree(runtime::testing::make_full_octree(3), dir / "tree");
  const auto frames = dir / "frames";
  const CliRun run = octolod("--json walk " + (dir / "tree").string() +
                              " --path orbit --frames 25 --fps 0 --budget 1M --frames-png " + frames.string() +
                              " --frames-png-every 10",
                          dir);
  ASSERT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.json.at("frames_png"), 3);
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(frames)) names.insert(entry.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"frame_000000.png", "frame_000010.png", "frame_000020.png"}));
  const Picture last = read_png(frames / "frame_000020.png");
  EXPECT_EQ(last.width, 960);
  EXPECT_EQ(last.height, 540);
  std::filesystem::remove_all(dir);
}

// A walk over a damaged tree still reports what it measured (the failed loads among it), but
// exits as bad input, naming the files: a script must not take it for a clean run.
TEST_F(RenderCli, WalkOverADamagedTreeReportsAndFails) {
  const auto dir = scratch_dir("walk_damaged");
  runtime::testing::write_tree(runtime::testing::make_full_octree(2), dir / "tree");
  ASSERT_GT(damage_node_files(dir / "tree"), 0u);
  // a second of replay at 60 fps: the loader threads have long tried these small files by its end
  const CliRun run = octolod("--json walk " + (dir / "tree").string() + " --path orbit --frames 60 --fps 60", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_GT(run.json.at("loads_failed").get<int>(), 0);
  const std::string errors = file_text(dir / "stderr.txt");
  EXPECT_NE(errors.find("lod0.bin"), std::string::npos) << errors;
  EXPECT_NE(errors.find("node LOD(s) failed to load"), std::string::npos) << errors;
  std::filesystem::remove_all(dir);
}

// Counts a typo could make huge are usage errors, not exhausted threads or memory, and a camera
// path that is a directory or broken JSON is named with what is wrong (line and column).
TEST_F(RenderCli, WalkRefusesHugeCountsAndBadCameraPaths) {
  const auto dir = scratch_dir("walk_bad");
  runtime::testing::write_tree(runtime::testing::make_full_octree(2), dir / "tree");
  const std::string walk = "walk " + (dir / "tree").string() + " --fps 0 ";
  for (const char* option : {"--frames 4294967295", "--frames 0", "--threads 100000", "--threads 0",
                             "--loads-in-flight 0", "--fps 1e-9", "--fps nan", "--sse 0", "--sse nan", "--budget 0"})
    EXPECT_EQ(octolod(walk + option, dir).exit_code, 1) << option;
  // outputs with nowhere to go fail before the replay (each file is written whole, after it)
  EXPECT_EQ(octolod(walk + "--frames 3 --csv " + (dir / "missing" / "w.csv").string(), dir).exit_code, 4);
  EXPECT_NE(file_text(dir / "stderr.txt").find("does not exist"), std::string::npos) << file_text(dir / "stderr.txt");
  EXPECT_EQ(octolod(walk + "--frames 3 --plot " + dir.string(), dir).exit_code, 4);
  EXPECT_NE(file_text(dir / "stderr.txt").find("it is a directory"), std::string::npos) << file_text(dir / "stderr.txt");
  EXPECT_EQ(octolod(walk + "--frames 3 --csv " + (dir / "w.csv").string(), dir).exit_code, 0);
  const std::string csv = file_text(dir / "w.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4);  // the header and 3 frames
  EXPECT_EQ(octolod(walk + "--frames 3 --path " + dir.string(), dir).exit_code, 4);
  EXPECT_NE(file_text(dir / "stderr.txt").find("cannot read the camera path: it is a directory"), std::string::npos)
      << file_text(dir / "stderr.txt");
  {
    std::ofstream(dir / "cut.json") << "{\"keyframes\": [{\"eye\": [1, 2, 3],\n \"target\": [0, 0";
  }
  EXPECT_EQ(octolod(walk + "--frames 3 --path " + (dir / "cut.json").string(), dir).exit_code, 2);
  const std::string errors = file_text(dir / "stderr.txt");
  EXPECT_NE(errors.find("line 2"), std::string::npos) << errors;
  EXPECT_EQ(errors.find("json.exception"), std::string::npos) << errors;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace octolod::cli
