// SPDX-License-Identifier: Apache-2.0
// Line and token scanning for the mesh readers.
#include "mesh/text_scanner.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <system_error>

namespace mica::detail {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// A token as shown in a message: at most 40 characters, control characters replaced.
std::string shown(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string s;
  for (char c : token.substr(0, kMax)) {
    const auto u = static_cast<unsigned char>(c);
    s += (u < 0x20 || u == 0x7f) ? '?' : c;
  }
  if (token.size() > kMax) s += "...";
  return s;
}

// For an unsigned decimal "mantissa[e exponent]" that std::from_chars found out of range:
// true if it is too small for a double (underflow), false if too large (overflow).
bool underflows(std::string_view s) {
  const std::size_t e = s.find_first_of("eE");
  const std::string_view mantissa = s.substr(0, e);
  std::int64_t exponent = 0;
  if (e != std::string_view::npos) {
    std::string_view digits = s.substr(e + 1);
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    const auto ec = std::from_chars(digits.data(), digits.data() + digits.size(), exponent).ec;
    // Far beyond any double's range, and small enough that adding a digit count cannot overflow
    // (an exponent of 2^63 - 1 itself parses, and wrapped the sum below).
    constexpr std::int64_t kBound = std::int64_t{1} << 40;
    if (ec == std::errc::result_out_of_range) exponent = digits.front() == '-' ? -kBound : kBound;
    exponent = std::clamp(exponent, -kBound, kBound);
  }
  // Power of ten of the leading nonzero digit (the mantissa has one, or it would be in range).
  const auto point = static_cast<std::int64_t>(std::min(mantissa.find('.'), mantissa.size()));
  const auto lead = static_cast<std::int64_t>(mantissa.find_first_not_of("0."));
  return (lead < point ? point - lead - 1 : point - lead) + exponent < 0;
}

// Parses all of `token` as a double as std::strtod does in the "C" locale: an optional sign,
// then a decimal or 0x-prefixed hexadecimal number, inf or nan. Values too small for a double
// read as zero; false if the token is not such a number or too large for a double.
bool parse_double(std::string_view token, double& value) {
  std::string_view s = token;
  const bool negative = !s.empty() && s.front() == '-';
  if (!s.empty() && (s.front() == '+' || s.front() == '-')) s.remove_prefix(1);
  auto format = std::chars_format::general;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    s.remove_prefix(2);
    format = std::chars_format::hex;
  }
  if (s.empty() || s.front() == '+' || s.front() == '-') return false;  // from_chars takes '-'
  const char* end = s.data() + s.size();
  const auto [stop, ec] = std::from_chars(s.data(), end, value, format);
  if (stop != end) return false;
  if (ec == std::errc::result_out_of_range && format == std::chars_format::general &&
      underflows(s)) {
    value = 0;
  } else if (ec != std::errc()) {
    return false;
  }
  if (negative) value = -value;
  return true;
}

}  // namespace

std::string_view first_token(std::string_view line) {
  std::size_t end = 0;
  while (end < line.size() && !is_space(line[end])) ++end;
  return line.substr(0, end);
}

LineReader::LineReader(std::string_view text, const std::string& name, std::string_view comment)
    : text_(text), name_(name), comment_(comment) {}

bool LineReader::advance() {
  while (pos_ < text_.size()) {
    std::size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    std::string_view line = text_.substr(pos_, end - pos_);
    if (!comment_.empty()) line = line.substr(0, line.find(comment_));
    line = trim(line);
    pos_ = end < text_.size() ? end + 1 : end;
    ++number_;
    if (!line.empty()) {
      line_ = line;
      return true;
    }
  }
  line_ = {};
  return false;
}

std::string_view LineReader::next(std::string_view what) {
  if (!advance()) expected(what, "end of file");
  return line_;
}

void LineReader::expect_end(std::string_view what) {
  if (advance()) expected(what, first_token(line_));
}

std::size_t LineReader::reservable(std::int64_t n, std::int64_t min_record_bytes) const {
  const auto bytes_left = static_cast<std::int64_t>(text_.size() - pos_);
  return static_cast<std::size_t>(std::min(n, bytes_left / min_record_bytes));
}

void LineReader::expected(std::string_view what, std::string_view got, Errc code) const {
  fail(code, name_ + ": line " + std::to_string(number_ > 0 ? number_ : 1) + ": expected " +
                 std::string(what) + ", got '" + shown(got) + "'");
}

std::string_view Fields::token(std::string_view what) {
  rest_ = trim(rest_);
  if (rest_.empty()) at_.expected(what, "end of line");
  last_ = first_token(rest_);
  rest_.remove_prefix(last_.size());
  return last_;
}

std::int64_t Fields::integer(std::string_view what, std::int64_t lo, std::int64_t hi) {
  const std::string_view tok = token(what);
  std::int64_t value = 0;
  const auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), value);
  if (ec != std::errc() || end != tok.data() + tok.size() || value < lo || value > hi) {
    at_.expected(what, tok);
  }
  return value;
}

double Fields::real(std::string_view what) {
  const std::string_view tok = token(what);
  double value = 0;
  if (!parse_double(tok, value) || !std::isfinite(value)) at_.expected(what, tok);
  return value;
}

void Fields::finish() {
  rest_ = trim(rest_);
  if (!rest_.empty()) at_.expected("end of line", first_token(rest_));
}

}  // namespace mica::detail
