#include "cola/cola.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <limits>

namespace pex::cola {

// ---------------------------------------------------------------- helpers --

std::string hex(std::uint32_t value) {
  char buffer[16];
  auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value, 16);
  (void)ec;
  std::string out(buffer, end);
  for (char& c : out) {
    if (c >= 'a' && c <= 'f') c = static_cast<char>(c - 'a' + 'A');
  }
  return out;
}

std::string hex_int32(std::int32_t value) { return hex(static_cast<std::uint32_t>(value)); }

namespace {

// A real as its IEEE 754 bits, always 8 hex digits.
std::string hex_real(float value) {
  std::string digits = hex(std::bit_cast<std::uint32_t>(value));
  return std::string(8 - digits.size(), '0') + digits;  // reals always carry 8 digits
}

std::string signed_decimal(std::int64_t value) {
  std::string out(1, value < 0 ? '-' : '+');
  out += std::to_string(value < 0 ? -value : value);
  return out;
}

}  // namespace

std::string frame(std::string_view body) {
  std::string out;
  out.reserve(body.size() + 2);
  out.push_back(kStx);
  out.append(body);
  out.push_back(kEtx);
  return out;
}

// ---------------------------------------------------------------- requests --

std::string set_access_mode_request(int user_level, std::uint32_t password_hash) {
  std::string body = "sMN SetAccessMode ";
  if (user_level >= 0 && user_level < 10) body.push_back('0');
  body += std::to_string(user_level);
  body.push_back(' ');
  const std::string hash = hex(password_hash);
  body.append(8 - hash.size(), '0');
  body += hash;
  return frame(body);
}

std::string set_scan_config_request(const ScanConfig& c) {
  return frame("sMN mLMPsetscancfg " + signed_decimal(c.frequency_centihz) + " +1 " +
               signed_decimal(c.angular_step_1e4deg) + " " + signed_decimal(c.start_angle_1e4deg) +
               " " + signed_decimal(c.stop_angle_1e4deg));
}

std::string scan_data_config_request(const ScanDataConfig& c) {
  // output channel "01 00", remission, resolution, unit 0 (digits), encoder "00 00",
  // position, device name, comment, time, output interval
  return frame(std::string("sWN LMDscandatacfg 01 00 ") + (c.remission ? "1" : "0") + " " +
               (c.remission_16bit ? "1" : "0") + " 0 00 00 0 0 0 " + (c.device_time ? "1" : "0") +
               " " + signed_decimal(c.output_interval));
}

std::string output_range_request(const ScanConfig& c) {
  return frame("sWN LMPoutputRange 1 " + hex(c.angular_step_1e4deg) + " " +
               hex_int32(c.start_angle_1e4deg) + " " + hex_int32(c.stop_angle_1e4deg));
}

std::string run_request() { return frame("sMN Run"); }
std::string start_measurement_request() { return frame("sMN LMCstartmeas"); }
std::string scan_output_request(bool enable) {
  return frame(std::string("sEN LMDscandata ") + (enable ? "1" : "0"));
}
std::string contamination_state_request() { return frame("sRN LCMstate"); }

// ------------------------------------------------------------------ framing --

std::vector<std::string> Framer::push(std::string_view bytes) {
  std::vector<std::string> out;
  for (char c : bytes) {
    if (c == kStx) {
      if (in_telegram_) ++counters_.truncated;  // the previous telegram never ended
      if (discarding_) discarding_ = false;
      in_telegram_ = true;
      partial_.clear();
      continue;
    }
    if (discarding_) {
      if (c == kEtx) discarding_ = false;
      continue;
    }
    if (!in_telegram_) {
      ++counters_.skipped_bytes;
      continue;
    }
    if (c == kEtx) {
      in_telegram_ = false;
      ++counters_.telegrams;
      out.push_back(std::move(partial_));
      partial_.clear();
      continue;
    }
    if (partial_.size() >= options_.max_telegram_bytes) {
      ++counters_.oversize;
      in_telegram_ = false;
      discarding_ = true;
      partial_.clear();
      partial_.shrink_to_fit();
      continue;
    }
    partial_.push_back(c);
  }
  return out;
}

void Framer::reset() {
  partial_.clear();
  in_telegram_ = false;
  discarding_ = false;
}

// ------------------------------------------------------------------ parsing --

std::variant<Telegram, ParseError> split_telegram(std::string_view body) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (start <= body.size()) {
    std::size_t space = body.find(' ', start);
    if (space == std::string_view::npos) space = body.size();
    if (space == start) {
      if (start == body.size()) break;
      return ParseError{"empty field (double space) at byte " + std::to_string(start)};
    }
    fields.emplace_back(body.substr(start, space - start));
    start = space + 1;
  }
  if (fields.empty()) return ParseError{"empty telegram"};
  const std::string& type = fields[0];
  if (type.size() != 3 || type[0] != 's') {
    return ParseError{"bad command type '" + type.substr(0, 16) + "'"};
  }
  for (char c : body) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7E) {
      return ParseError{"non-printable byte in telegram"};
    }
  }
  Telegram t;
  t.type = type;
  std::size_t first_arg = 1;
  if (type != "sFA" && fields.size() >= 2) {
    t.name = fields[1];
    first_arg = 2;
  }
  t.args.assign(fields.begin() + static_cast<std::ptrdiff_t>(first_arg), fields.end());
  return t;
}

std::optional<std::uint32_t> parse_uint(std::string_view token, std::uint32_t max_value) {
  if (token.empty() || token.size() > 11) return std::nullopt;
  std::uint64_t value = 0;
  const char* first = token.data();
  const char* last = token.data() + token.size();
  int base = 16;
  if (token[0] == '+') {
    base = 10;
    ++first;
  } else if (token[0] == '-') {
    return std::nullopt;
  }
  if (first == last) return std::nullopt;
  for (const char* p = first; p != last; ++p) {
    const bool digit = *p >= '0' && *p <= '9';
    const bool hex_upper = *p >= 'A' && *p <= 'F';
    const bool hex_lower = *p >= 'a' && *p <= 'f';
    if (!(digit || (base == 16 && (hex_upper || hex_lower)))) return std::nullopt;
  }
  auto [ptr, ec] = std::from_chars(first, last, value, base);
  if (ec != std::errc() || ptr != last || value > max_value) return std::nullopt;
  return static_cast<std::uint32_t>(value);
}

std::optional<std::int32_t> parse_int32(std::string_view token) {
  if (token.empty()) return std::nullopt;
  if (token[0] == '-' || token[0] == '+') {
    if (token.size() < 2 || token.size() > 11) return std::nullopt;
    std::int64_t value = 0;
    const char* first = token.data() + 1;
    for (const char* p = first; p != token.data() + token.size(); ++p) {
      if (*p < '0' || *p > '9') return std::nullopt;
    }
    auto [ptr, ec] = std::from_chars(first, token.data() + token.size(), value, 10);
    if (ec != std::errc() || ptr != token.data() + token.size()) return std::nullopt;
    if (token[0] == '-') value = -value;
    if (value < std::numeric_limits<std::int32_t>::min() ||
        value > std::numeric_limits<std::int32_t>::max()) {
      return std::nullopt;
    }
    return static_cast<std::int32_t>(value);
  }
  auto raw = parse_uint(token, 0xFFFFFFFFu);
  if (!raw) return std::nullopt;
  return static_cast<std::int32_t>(*raw);  // two's complement, as the device sends it
}

std::optional<float> parse_real(std::string_view token) {
  if (token.size() != 8) return std::nullopt;
  auto raw = parse_uint(token, 0xFFFFFFFFu);
  if (!raw) return std::nullopt;
  float value = std::bit_cast<float>(*raw);
  if (!std::isfinite(value)) return std::nullopt;
  return value;
}

const Channel* ScanData::find_channel(std::string_view content) const {
  for (const auto& c : channels16) {
    if (c.content == content) return &c;
  }
  for (const auto& c : channels8) {
    if (c.content == content) return &c;
  }
  return nullptr;
}

namespace {

// Reads typed fields from the argument list in order; the first failure sticks
// and names the field, so the caller can stop at any point and report it.
class FieldReader {
 public:
  explicit FieldReader(const std::vector<std::string>& args) : args_(args) {}

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  std::size_t remaining() const { return args_.size() - next_; }

  std::uint32_t uint(const char* field, std::uint32_t max_value) {
    const std::string* token = take(field);
    if (!token) return 0;
    auto value = parse_uint(*token, max_value);
    if (!value) {
      fail(field, "bad number '" + token->substr(0, 16) + "'");
      return 0;
    }
    return *value;
  }
  std::int32_t int32(const char* field) {
    const std::string* token = take(field);
    if (!token) return 0;
    auto value = parse_int32(*token);
    if (!value) {
      fail(field, "bad number '" + token->substr(0, 16) + "'");
      return 0;
    }
    return *value;
  }
  float real(const char* field) {
    const std::string* token = take(field);
    if (!token) return 0.0f;
    auto value = parse_real(*token);
    if (!value) {
      fail(field, "bad real '" + token->substr(0, 16) + "'");
      return 0.0f;
    }
    return *value;
  }
  std::string text(const char* field) {
    const std::string* token = take(field);
    return token ? *token : std::string();
  }
  // A CoLa-A string with its length in front ("5 LMS11"); it may contain spaces.
  std::string counted_string(const char* field) {
    std::uint32_t length = uint(field, 255);
    std::string out;
    while (ok() && out.size() < length) {
      if (!out.empty()) out.push_back(' ');
      const std::string* token = take(field);
      if (!token) break;
      out += *token;
    }
    if (ok() && out.size() != length) fail(field, "string length does not match");
    return out;
  }
  void fail(const char* field, const std::string& why) {
    if (error_.empty()) error_ = std::string(field) + ": " + why;
  }

 private:
  const std::string* take(const char* field) {
    if (!ok()) return nullptr;
    if (next_ >= args_.size()) {
      fail(field, "telegram ends early");
      return nullptr;
    }
    return &args_[next_++];
  }

  const std::vector<std::string>& args_;
  std::size_t next_ = 0;
  std::string error_;
};

void read_channels(FieldReader& r, std::vector<Channel>& out, bool eight_bit) {
  const std::uint32_t count = r.uint(eight_bit ? "number of 8-bit channels" : "number of 16-bit channels",
                                     0xFFFF);
  if (!r.ok()) return;
  if (count > kMaxChannels) {
    r.fail("channels", "too many channels (" + std::to_string(count) + ")");
    return;
  }
  for (std::uint32_t i = 0; i < count && r.ok(); ++i) {
    Channel c;
    c.content = r.text("channel content");
    if (r.ok() && (c.content.size() != 5)) r.fail("channel content", "not 5 characters: '" + c.content + "'");
    c.scale_factor = r.real("scale factor");
    c.scale_offset = r.real("scale factor offset");
    c.start_angle_1e4deg = r.int32("start angle");
    c.angular_step_1e4deg = static_cast<std::uint16_t>(r.uint("angular step", 0xFFFF));
    const std::uint32_t n = r.uint("number of data", 0xFFFF);
    if (!r.ok()) return;
    if (n > kMaxChannelValues) {
      r.fail("number of data", std::to_string(n) + " values exceed the limit");
      return;
    }
    if (n > r.remaining()) {
      r.fail("data", "telegram ends early (" + std::to_string(n) + " values announced)");
      return;
    }
    c.data.reserve(n);
    for (std::uint32_t k = 0; k < n && r.ok(); ++k) {
      c.data.push_back(static_cast<std::uint16_t>(r.uint("data", eight_bit ? 0xFF : 0xFFFF)));
    }
    out.push_back(std::move(c));
  }
}

}  // namespace

std::variant<ScanData, ParseError> parse_scan_data(const Telegram& telegram) {
  if (telegram.name != "LMDscandata" || (telegram.type != "sRA" && telegram.type != "sSN")) {
    return ParseError{"not a scan telegram: " + telegram.type + " " + telegram.name};
  }
  ScanData s;
  FieldReader r(telegram.args);
  s.version = static_cast<std::uint16_t>(r.uint("version", 0xFFFF));
  s.device_number = static_cast<std::uint16_t>(r.uint("device number", 0xFFFF));
  s.serial_number = r.uint("serial number", 0xFFFFFFFF);
  s.device_status[0] = static_cast<std::uint8_t>(r.uint("device status", 0xFF));
  s.device_status[1] = static_cast<std::uint8_t>(r.uint("device status", 0xFF));
  s.telegram_counter = static_cast<std::uint16_t>(r.uint("telegram counter", 0xFFFF));
  s.scan_counter = static_cast<std::uint16_t>(r.uint("scan counter", 0xFFFF));
  s.time_since_startup_us = r.uint("time since start-up", 0xFFFFFFFF);
  s.time_of_transmission_us = r.uint("time of transmission", 0xFFFFFFFF);
  s.digital_inputs[0] = static_cast<std::uint8_t>(r.uint("digital inputs", 0xFF));
  s.digital_inputs[1] = static_cast<std::uint8_t>(r.uint("digital inputs", 0xFF));
  s.digital_outputs[0] = static_cast<std::uint8_t>(r.uint("digital outputs", 0xFF));
  s.digital_outputs[1] = static_cast<std::uint8_t>(r.uint("digital outputs", 0xFF));
  s.reserved = static_cast<std::uint16_t>(r.uint("reserved", 0xFFFF));
  s.scan_frequency_centihz = r.uint("scan frequency", 0xFFFFFFFF);
  s.measurement_frequency_100hz = r.uint("measurement frequency", 0xFFFFFFFF);
  const std::uint32_t encoders = r.uint("number of encoders", 0xFFFF);
  if (r.ok() && encoders > kMaxEncoders) r.fail("number of encoders", "too many");
  for (std::uint32_t i = 0; i < encoders && r.ok(); ++i) {
    ScanData::Encoder e;
    e.position = r.uint("encoder position", 0xFFFFFFFF);
    e.speed = static_cast<std::uint16_t>(r.uint("encoder speed", 0xFFFF));
    s.encoders.push_back(e);
  }
  read_channels(r, s.channels16, false);
  read_channels(r, s.channels8, true);
  // Position block
  s.has_position = r.uint("position flag", 1) == 1;
  if (s.has_position) {
    for (float& p : s.position) p = r.real("position");
    s.rotation_type = static_cast<std::uint8_t>(r.uint("rotation type", 3));
  }
  if (r.uint("device name flag", 1) == 1) {
    s.device_name = r.counted_string("device name");
    if (r.ok() && s.device_name.empty()) r.fail("device name", "flag set but empty");
  }
  if (r.uint("comment flag", 1) == 1) {
    s.comment = r.counted_string("comment");
    if (r.ok() && s.comment.empty()) r.fail("comment", "flag set but empty");
  }
  if (r.uint("time flag", 1) == 1) {
    DeviceDateTime t;
    t.year = static_cast<std::uint16_t>(r.uint("year", 9999));
    t.month = static_cast<std::uint8_t>(r.uint("month", 12));
    t.day = static_cast<std::uint8_t>(r.uint("day", 31));
    t.hour = static_cast<std::uint8_t>(r.uint("hour", 23));
    t.minute = static_cast<std::uint8_t>(r.uint("minute", 59));
    t.second = static_cast<std::uint8_t>(r.uint("second", 59));
    t.microsecond = r.uint("microsecond", 999999);
    s.date_time = t;
  }
  if (r.uint("event flag", 1) == 1) {
    s.event_type = r.text("event type");
    r.uint("event encoder position", 0xFFFFFFFF);
    r.uint("event time", 0xFFFFFFFF);
    r.int32("event angle");
  }
  if (!r.ok()) return ParseError{"LMDscandata: " + r.error()};
  if (r.remaining() != 0) {
    return ParseError{"LMDscandata: " + std::to_string(r.remaining()) + " fields left over"};
  }
  if (s.channels16.empty() && s.channels8.empty()) return ParseError{"LMDscandata: no channels"};
  return s;
}

std::optional<ContaminationLevel> contamination_level(const Telegram& telegram) {
  if (telegram.type != "sRA" || telegram.name != "LCMstate" || telegram.args.size() != 1) return std::nullopt;
  const auto level = parse_uint(telegram.args[0], 3);
  if (!level) return std::nullopt;
  return static_cast<ContaminationLevel>(*level);
}

std::vector<float> distances_m(const Channel& channel) {
  std::vector<float> out;
  out.reserve(channel.data.size());
  for (std::uint16_t raw : channel.data) {
    if (raw < kFirstValidDistance) {
      out.push_back(std::numeric_limits<float>::quiet_NaN());
    } else {
      out.push_back((static_cast<float>(raw) * channel.scale_factor + channel.scale_offset) * 0.001f);
    }
  }
  return out;
}

// ----------------------------------------------------------- stream parser --

std::vector<StreamEvent> StreamParser::push(std::string_view bytes) {
  std::vector<StreamEvent> events;
  for (std::string& body : framer_.push(bytes)) {
    auto split = split_telegram(body);
    if (auto* error = std::get_if<ParseError>(&split)) {
      ++counters_.malformed;
      events.emplace_back(ErrorEvent{error->message});
      continue;
    }
    Telegram& telegram = std::get<Telegram>(split);
    if (telegram.name == "LMDscandata" && (telegram.type == "sSN" || telegram.type == "sRA")) {
      auto scan = parse_scan_data(telegram);
      if (auto* error = std::get_if<ParseError>(&scan)) {
        ++counters_.malformed;
        events.emplace_back(ErrorEvent{error->message});
      } else {
        ++counters_.scans;
        events.emplace_back(ScanEvent{std::move(std::get<ScanData>(scan))});
      }
      continue;
    }
    ++counters_.replies;
    events.emplace_back(ReplyEvent{std::move(telegram)});
  }
  return events;
}

// ------------------------------------------------------------- sensor side --

namespace {

void append(std::string& out, const std::string& field) {
  out.push_back(' ');
  out += field;
}

void append_channels(std::string& out, const std::vector<Channel>& channels) {
  append(out, hex(static_cast<std::uint32_t>(channels.size())));
  for (const Channel& c : channels) {
    append(out, c.content);
    append(out, hex_real(c.scale_factor));
    append(out, hex_real(c.scale_offset));
    append(out, hex_int32(c.start_angle_1e4deg));
    append(out, hex(c.angular_step_1e4deg));
    append(out, hex(static_cast<std::uint32_t>(c.data.size())));
    for (std::uint16_t v : c.data) append(out, hex(v));
  }
}

void append_counted(std::string& out, const std::string& text) {
  append(out, hex(static_cast<std::uint32_t>(text.size())));
  append(out, text);
}

}  // namespace

std::string encode_scan_data(const ScanData& s, bool as_poll_answer) {
  std::string body = as_poll_answer ? "sRA LMDscandata" : "sSN LMDscandata";
  body.reserve(64 + 4 * 1100);
  append(body, hex(s.version));
  append(body, hex(s.device_number));
  append(body, hex(s.serial_number));
  append(body, hex(s.device_status[0]));
  append(body, hex(s.device_status[1]));
  append(body, hex(s.telegram_counter));
  append(body, hex(s.scan_counter));
  append(body, hex(s.time_since_startup_us));
  append(body, hex(s.time_of_transmission_us));
  append(body, hex(s.digital_inputs[0]));
  append(body, hex(s.digital_inputs[1]));
  append(body, hex(s.digital_outputs[0]));
  append(body, hex(s.digital_outputs[1]));
  append(body, hex(s.reserved));
  append(body, hex(s.scan_frequency_centihz));
  append(body, hex(s.measurement_frequency_100hz));
  append(body, hex(static_cast<std::uint32_t>(s.encoders.size())));
  for (const auto& e : s.encoders) {
    append(body, hex(e.position));
    append(body, hex(e.speed));
  }
  append_channels(body, s.channels16);
  append_channels(body, s.channels8);
  append(body, s.has_position ? "1" : "0");
  if (s.has_position) {
    for (float p : s.position) append(body, hex_real(p));
    append(body, hex(s.rotation_type));
  }
  append(body, s.device_name.empty() ? "0" : "1");
  if (!s.device_name.empty()) append_counted(body, s.device_name);
  append(body, s.comment.empty() ? "0" : "1");
  if (!s.comment.empty()) append_counted(body, s.comment);
  append(body, s.date_time ? "1" : "0");
  if (s.date_time) {
    const DeviceDateTime& t = *s.date_time;
    for (std::uint32_t v : {std::uint32_t{t.year}, std::uint32_t{t.month}, std::uint32_t{t.day},
                            std::uint32_t{t.hour}, std::uint32_t{t.minute}, std::uint32_t{t.second},
                            t.microsecond}) {
      append(body, hex(v));
    }
  }
  append(body, "0");  // no event block
  return frame(body);
}

std::string encode_reply(std::string_view type, std::string_view name,
                         const std::vector<std::string>& args) {
  std::string body(type);
  if (!name.empty()) append(body, std::string(name));
  for (const auto& a : args) append(body, a);
  return frame(body);
}

}  // namespace pex::cola

namespace pex::cola {

std::int64_t DeviceClock::unwrap(std::uint32_t raw) {
  if (have_last_ && raw < last_raw_ && last_raw_ - raw > 0x80000000u) ++wraps_;
  have_last_ = true;
  last_raw_ = raw;
  return wraps_ * (std::int64_t{1} << 32) + raw;
}

std::int64_t DeviceClock::robust_minimum() const {
  // The k-th smallest, k a tenth of the samples: transport delay only adds
  // to an offset sample, so the smallest are the truest, but a receive clock
  // that was behind (a simulated clock whose tick came after the telegram)
  // makes a few samples too small; the minimum itself would keep such a
  // sample for the whole window.
  std::vector<std::int64_t> sorted(offsets_);
  const auto k = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 10);
  std::nth_element(sorted.begin(), k, sorted.end());
  return *k;
}

void DeviceClock::reset() {
  have_last_ = false;
  wraps_ = 0;
  offsets_.clear();
  next_ = 0;
  outlier_run_.clear();
}

DeviceClock::Mapped DeviceClock::map(std::uint32_t scan_device_us, std::uint32_t transmit_device_us,
                                     std::int64_t host_receive_us) {
  // The transmission time is the later one; unwrap it first, then place the
  // scan time just before it (modulo 2^32).
  const std::int64_t transmit = unwrap(transmit_device_us);
  const std::int64_t scan = transmit - static_cast<std::int64_t>(
                                           static_cast<std::uint32_t>(transmit_device_us - scan_device_us));
  const std::int64_t sample = host_receive_us - transmit;
  const auto near = [&](std::int64_t offset_us) {
    return sample >= offset_us - options_.max_step_us && sample <= offset_us + options_.max_step_us;
  };
  if (!offsets_.empty() && offsets_.size() >= options_.settled_samples) {
    const std::int64_t best = robust_minimum();
    if (!near(best)) {
      ++outliers_;
      const bool agrees = !outlier_run_.empty() && near(outlier_run_.front().offset_us);
      if (!agrees || outlier_run_.size() >= std::max<std::size_t>(options_.window, 1)) outlier_run_.clear();
      outlier_run_.push_back({transmit, sample});
      if (transmit - outlier_run_.front().transmit_us < options_.new_offset_after_us) return Mapped{scan, scan + best};
      // The new offset held: the host clock stepped. Afresh on the run.
      ++resets_;
      offsets_.clear();
      next_ = 0;
      for (const Sample& s : outlier_run_) offsets_.push_back(s.offset_us);
      outlier_run_.clear();
      return Mapped{scan, scan + robust_minimum()};
    }
    outlier_run_.clear();
  }
  if (offsets_.size() < std::max<std::size_t>(options_.window, 1)) {
    offsets_.push_back(sample);
  } else {
    offsets_[next_] = sample;
    next_ = (next_ + 1) % offsets_.size();
  }
  return Mapped{scan, scan + robust_minimum()};
}

}  // namespace pex::cola
