// SPDX-License-Identifier: Apache-2.0
// Scripted stylus motion for the simulated devices: a position as a function of time, given
// as a function or as samples read from a CSV file.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace mica {

// Position (m) at time t (s). Called on the servo thread: it must not block.
using Trajectory = std::function<Vec3(double t)>;

// Samples joined by straight lines, held at the first before it and at the last after it.
class SampledTrajectory {
 public:
  // At least one sample, `times` finite and strictly increasing, as many positions as times;
  // Errc::InvalidArgument otherwise.
  SampledTrajectory(std::vector<double> times, Vec3List positions);

  // Neither allocates nor throws; exact at the samples.
  Vec3 operator()(double t) const;

  const std::vector<double>& times() const { return times_; }
  const Vec3List& positions() const { return positions_; }

 private:
  std::vector<double> times_;
  Vec3List positions_;
};

// Reads rows "t,x,y,z" (s, m): one row a line, fields separated by commas and optionally
// blanks; blank lines and lines starting with '#' are skipped; the first line with content is
// a header, and skipped, if none of its fields is a number. Times must increase strictly.
// Errc::Io if the file cannot be read, Errc::Parse "<path>: line N: ..." if it is malformed.
SampledTrajectory load_trajectory_csv(const std::string& path);

}  // namespace mica
