// SPDX-License-Identifier: Apache-2.0
#include "devices/trajectory.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>

#include "core/error.hpp"
#include "mesh/text_scanner.hpp"

namespace mica {

SampledTrajectory::SampledTrajectory(std::vector<double> times, Vec3List positions)
    : times_(std::move(times)), positions_(std::move(positions)) {
  if (times_.empty()) fail(Errc::InvalidArgument, "a sampled trajectory needs at least one sample");
  if (times_.size() != positions_.size())
    fail(Errc::InvalidArgument, "a sampled trajectory needs as many positions as times");
  for (std::size_t i = 0; i < times_.size(); ++i) {
    if (!std::isfinite(times_[i]) || !positions_[i].allFinite())
      fail(Errc::InvalidArgument, "sample " + std::to_string(i) + " of a sampled trajectory is not finite");
    if (i > 0 && !(times_[i] > times_[i - 1]))
      fail(Errc::InvalidArgument, "the times of a sampled trajectory must increase strictly");
  }
}

Vec3 SampledTrajectory::operator()(double t) const {
  // Written so that a NaN time reads the first sample rather than past the end.
  if (!(t > times_.front())) return positions_.front();
  if (t >= times_.back()) return positions_.back();
  const std::size_t j = std::size_t(std::upper_bound(times_.begin(), times_.end(), t) - times_.begin()) - 1;
  const double s = (t - times_[j]) / (times_[j + 1] - times_[j]);
  return positions_[j] + s * (positions_[j + 1] - positions_[j]);
}

namespace {

std::string_view trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  for (;;) {
    const std::size_t comma = line.find(',');
    fields.push_back(trim(line.substr(0, comma)));
    if (comma == std::string_view::npos) return fields;
    line.remove_prefix(comma + 1);
  }
}

// The whole field as a finite number; from_chars, unlike strtod, ignores the C locale.
std::optional<double> finite_number(std::string_view field) {
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  double value = 0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (field.empty() || ec != std::errc() || end != field.data() + field.size() || !std::isfinite(value))
    return std::nullopt;
  return value;
}

// A regular file of at most 64 MiB (a FIFO or /dev/zero is refused, not waited on or read forever).
std::string read_file(const std::string& path) { return detail::read_text_file(path, std::size_t(64) << 20); }

}  // namespace

SampledTrajectory load_trajectory_csv(const std::string& path) {
  const std::string text = read_file(path);
  static const char* const names[4] = {"t", "x", "y", "z"};
  std::vector<double> times;
  Vec3List positions;
  bool first_content = true;
  std::size_t begin = 0;
  for (int64_t number = 1; begin < text.size(); ++number) {
    const std::size_t end = std::min(text.find('\n', begin), text.size());
    const std::string_view line = trim(std::string_view(text).substr(begin, end - begin));
    begin = end + 1;
    if (line.empty() || line.front() == '#') continue;
    const std::string at = path + ": line " + std::to_string(number) + ": ";
    const auto fields = split_fields(line);
    const bool header = first_content && std::none_of(fields.begin(), fields.end(), [](std::string_view f) {
                          return finite_number(f).has_value();
                        });
    first_content = false;
    if (header) continue;
    if (fields.size() != 4)
      fail(Errc::Parse, at + "expected 4 comma-separated values t,x,y,z, got " + std::to_string(fields.size()));
    double row[4];
    for (int k = 0; k < 4; ++k) {
      const auto value = finite_number(fields[k]);
      if (!value) fail(Errc::Parse, at + names[k] + " is not a finite number: '" + std::string(fields[k]) + "'");
      row[k] = *value;
    }
    if (!times.empty() && !(row[0] > times.back())) {
      std::ostringstream msg;
      msg.precision(17);
      msg << at << "t = " << row[0] << " s does not come after the previous row's t = " << times.back() << " s";
      fail(Errc::Parse, msg.str());
    }
    times.push_back(row[0]);
    positions.emplace_back(row[1], row[2], row[3]);
  }
  if (times.empty()) fail(Errc::Parse, path + ": no samples: expected rows t,x,y,z (s, m)");
  return SampledTrajectory(std::move(times), std::move(positions));
}

}  // namespace mica
