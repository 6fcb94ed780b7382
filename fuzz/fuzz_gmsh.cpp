// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: parse_gmsh on the input bytes (Gmsh 2.2 / 4.1 ASCII).
// Seeds: fuzz/corpus/gmsh. Dictionary: fuzz/dict/gmsh.dict.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_common.hpp"
#include "mesh/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string kName = "fuzz.msh";
  const std::string_view text = mica_fuzz::as_text(data, size);
  mica_fuzz::run_guarded([&] { mica_fuzz::check_parsed_mesh(mica::parse_gmsh(text, kName)); },
                         [&](const mica::Error& e) { mica_fuzz::check_parse_error(e, kName); });
  return 0;
}
