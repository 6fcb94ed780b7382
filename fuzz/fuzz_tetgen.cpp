// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: parse_tetgen on the input split at its first NUL byte into the .node text
// (before) and the .ele text (after; empty when there is no NUL).
// Seeds: fuzz/corpus/tetgen. Dictionary: fuzz/dict/tetgen.dict.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_common.hpp"
#include "mesh/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string kNode = "fuzz.node";
  static const std::string kEle = "fuzz.ele";
  const mica_fuzz::TetgenTexts in = mica_fuzz::split_tetgen(mica_fuzz::as_text(data, size));
  mica_fuzz::run_guarded(
      [&] { mica_fuzz::check_parsed_mesh(mica::parse_tetgen(in.node, in.ele, kNode, kEle)); },
      [&](const mica::Error& e) { mica_fuzz::check_parse_error(e, kNode, kEle); });
  return 0;
}
