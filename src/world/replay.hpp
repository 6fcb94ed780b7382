// SPDX-License-Identifier: Apache-2.0
// Replaying a recording (recording.hpp) into a world made with the recorded settings: each call
// is made again in order, devices become inert stand-ins (null devices with the recorded settings,
// so that saved states restore), and each step is handed the poses the devices gave their tools.
// A step whose fingerprint differs from the recording's is reported: the replay diverged.
#pragma once
#include <string>
#include <vector>

#include "world/recording.hpp"

namespace mica {

class Replay {
 public:
  // Checks the header; throws Error(Parse) for a file that is not a recording or is of another
  // format or machine kind, Error(Truncated) for one that ends inside its header.
  explicit Replay(std::vector<uint8_t> bytes, std::string name = "the recording");
  // Reads the whole file; throws Error(Io) naming the path.
  static Replay open(const std::string& path);

  const WorldSettings& settings() const { return settings_; }

  // Makes the recorded calls up to the next step, then that step, on `world` (made with
  // settings() and changed only by this replay); false at the end entry (the calls after the last
  // step were made). Throws Error(Truncated) when the file ends before its end entry (format 1,
  // without one, ends with its file instead: false), Error(Parse) for a corrupt entry,
  // Error(Diverged) when a call or the step does not do what it did when recorded, and the step's
  // own error when it failed when recorded too.
  bool next_step(World& world);
  int64_t steps() const { return steps_; }  // steps replayed (or attempted) so far

 private:
  void apply(World& world, RecordKind kind, ByteReader& in);
  void end(ByteReader& in);  // checks the end entry (the last one)
  [[noreturn]] void diverged(const std::string& what) const;
  [[noreturn]] void cut_short(const std::string& where) const;
  std::vector<uint8_t> bytes_;
  std::string name_;
  uint32_t version_ = 0;
  bool ended_ = false;
  size_t at_ = 0;
  int64_t steps_ = 0;
  WorldSettings settings_;
  std::vector<AdoptedPose> poses_;
};

}  // namespace mica
