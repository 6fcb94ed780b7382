// SPDX-License-Identifier: Apache-2.0
// Writing a recording (recording.hpp): the file, and the world's start and stop.
#include "world/recording.hpp"

#include <cerrno>
#include <cstring>

namespace mica {

Recorder::Recorder(const std::string& path, const WorldSettings& settings) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) fail(Errc::Io, "cannot open '" + path + "' to record into: " + std::strerror(errno));
  ByteWriter header;
  header.put_bytes(kRecordingMagic, sizeof kRecordingMagic);
  header.put(kRecordingVersion);
  header.put(kByteLayout);
  put(header, settings);
  if (std::fwrite(header.bytes().data(), 1, header.bytes().size(), file_) != header.bytes().size()) {
    std::fclose(file_);
    fail(Errc::Io, "cannot write to '" + path + "': " + std::strerror(errno));
  }
}

Recorder::~Recorder() { close(); }

void Recorder::append(RecordKind kind, const std::vector<uint8_t>& payload) {
  if (!file_ || !error_.empty()) return;
  const RecordEntryHeader head{uint32_t(kind), 0, payload.size()};
  const bool ok = std::fwrite(&head, sizeof head, 1, file_) == 1 &&
                  std::fwrite(payload.data(), 1, payload.size(), file_) == payload.size() &&
                  // A step ends an entry group: flushed, so a crash of the host keeps every step before it.
                  (kind != RecordKind::Step || std::fflush(file_) == 0);
  if (!ok) error_ = "writing '" + path_ + "' failed: " + std::strerror(errno);
  if (kind == RecordKind::Step) ++steps_;
}

bool Recorder::close() noexcept {
  if (!file_) return true;
  write(RecordKind::End, steps_);  // skipped after a failed write: the file then reads as cut short
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  return closed;
}

void Recorder::stop() {
  if (!close() && error_.empty()) error_ = "closing '" + path_ + "' failed: " + std::strerror(errno);
  if (!error_.empty()) fail(Errc::Io, "the recording is incomplete: " + error_);
}

void World::start_recording(const std::string& path) {
  if (recorder_) fail(Errc::WrongState, "the world is already recording: stop that recording first");
  // A replay builds its world from the recording and must be handed the same ids.
  if (bodies_.slots_used() || tools_.slots_used() || lpcs_.slots_used() || devices_.slots_used())
    fail(Errc::WrongState, "a recording starts from a new world (its replay builds the world from it): start "
                           "recording before adding any body, tool, constraint or device");
  recorder_ = std::make_unique<Recorder>(path, settings_);
}

void World::stop_recording() {
  if (!recorder_) fail(Errc::WrongState, "the world is not recording");
  std::unique_ptr<Recorder> recorder = std::move(recorder_);
  recorder->stop();
}

}  // namespace mica
