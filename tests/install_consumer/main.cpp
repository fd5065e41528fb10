// Links the installed runtime and formats libraries: decodes a node file it encodes itself.
#include <cstdio>

#include "octolod/formats/node_file.h"

int main() {
  octolod::NodeMesh mesh;
  mesh.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  mesh.indices = {0, 1, 2};
  auto bytes = octolod::encode_node_file(mesh);
  auto back = octolod::decode_node_file(bytes, "consumer");
  if (!back.ok() || !(back.value() == mesh)) return 1;
  std::puts("consumer: ok");
  return 0;
}
