#pragma once
// SICK LMS1xx CoLa-A ("Command Language ASCII") telegrams, as described in
// SICK's telegram listing for the LMS1xx/LMS5xx/TiM family:
//   <STX>command-type SPC command-name SPC arg SPC arg ...<ETX>
// STX = 0x02, ETX = 0x03, fields separated by one space. Numbers in device
// answers are upper-case hexadecimal without leading zeros (signed values as
// two's complement of their width); numbers in requests are either hex or
// decimal with an explicit sign ("+2500", "-450000"). Reals (scale factor) are
// the 8 hex digits of an IEEE-754 single.
//
// This library has no I/O: it builds request bytes, splits a byte stream into
// telegrams, parses them, and encodes the sensor side (used by the simulator).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace pex::cola {

inline constexpr char kStx = '\x02';
inline constexpr char kEtx = '\x03';

// ---------------------------------------------------------------- requests --

// Wraps a telegram body in STX ... ETX.
std::string frame(std::string_view body);

// User levels of SetAccessMode and the password hashes SICK documents for them.
inline constexpr int kUserLevelMaintenance = 2;
inline constexpr int kUserLevelAuthorizedClient = 3;
inline constexpr std::uint32_t kPasswordAuthorizedClient = 0xF4724744;
inline constexpr std::uint32_t kPasswordMaintenance = 0xB21ACE26;

// sMN SetAccessMode <level> <hash>; the answer is "sAN SetAccessMode 1" on success.
std::string set_access_mode_request(int user_level, std::uint32_t password_hash);

// Scan configuration in the device's units.
struct ScanConfig {
  std::uint32_t frequency_centihz = 2500;        // 1/100 Hz: 2500 = 25 Hz
  std::uint32_t angular_step_1e4deg = 5000;      // 1/10000 deg: 5000 = 0.5 deg
  std::int32_t start_angle_1e4deg = -450000;     // -45 deg (device frame: 0 deg = right of the x axis)
  std::int32_t stop_angle_1e4deg = 2250000;      // 225 deg
};
// sMN mLMPsetscancfg +freq +1 +step +start +stop  (one "sector", decimal with sign)
std::string set_scan_config_request(const ScanConfig& config);

// What each LMDscandata telegram carries (sWN LMDscandatacfg).
struct ScanDataConfig {
  bool remission = true;          // add the RSSI1 channel
  bool remission_16bit = false;   // RSSI resolution: false = 8 bit, true = 16 bit
  bool device_time = false;       // append the device's date/time block
  std::uint16_t output_interval = 1;  // every n-th scan
};
// sWN LMDscandatacfg 01 00 <rem> <res> 0 00 00 0 0 0 <time> +<interval>
std::string scan_data_config_request(const ScanDataConfig& config);
// sWN LMPoutputRange 1 <step> <start> <stop> (hex): the angular range output
std::string output_range_request(const ScanConfig& config);
// sMN Run: leave the authorized-client level, apply the configuration.
std::string run_request();
// sMN LMCstartmeas: start the laser and motor.
std::string start_measurement_request();
// sEN LMDscandata 1|0: start/stop continuous scan output.
std::string scan_output_request(bool enable);
// sRN LCMstate: the lens contamination measurement; the
// answer is "sRA LCMstate <level>" (contamination_level below).
std::string contamination_state_request();

// ------------------------------------------------------------------ framing --

// Splits a byte stream into telegram bodies. Feed it what a read() returned;
// it keeps partial telegrams between calls. Bytes outside STX..ETX are
// skipped and counted; a telegram that is cut off by a new STX or grows past
// max_telegram_bytes is dropped and counted. Never throws on any input.
class Framer {
 public:
  struct Options {
    std::size_t max_telegram_bytes = 65536;  // a 541-beam scan with RSSI is ~5 KiB
  };
  struct Counters {
    std::uint64_t telegrams = 0;        // complete bodies returned
    std::uint64_t skipped_bytes = 0;    // garbage outside any telegram
    std::uint64_t truncated = 0;        // telegrams cut off by a new STX
    std::uint64_t oversize = 0;         // telegrams dropped for length
  };

  Framer() = default;
  explicit Framer(Options options) : options_(options) {}

  // Appends bytes; returns the bodies (without STX/ETX) completed by them, in order.
  std::vector<std::string> push(std::string_view bytes);
  // Forgets a partial telegram (after a reconnect).
  void reset();
  const Counters& counters() const { return counters_; }

 private:
  Options options_;
  Counters counters_;
  std::string partial_;
  bool in_telegram_ = false;
  bool discarding_ = false;  // inside an oversize telegram, waiting for its ETX
};

// ------------------------------------------------------------------ parsing --

// A telegram split into its fields: type ("sRA", "sSN", "sAN", "sFA", ...),
// name ("LMDscandata"; empty for sFA) and the remaining arguments.
struct Telegram {
  std::string type;
  std::string name;
  std::vector<std::string> args;
};

struct ParseError {
  std::string message;
};

// Splits a body at single spaces. An empty body or a type that is not three
// letters starting with 's' is an error.
std::variant<Telegram, ParseError> split_telegram(std::string_view body);

// Number parsing for arguments: hex ("FFF92230") or decimal with sign ("+2500").
std::optional<std::uint32_t> parse_uint(std::string_view token, std::uint32_t max_value);
std::optional<std::int32_t> parse_int32(std::string_view token);  // hex is two's complement
std::optional<float> parse_real(std::string_view token);           // 8 hex digits, IEEE-754

// One measurement channel of an LMDscandata telegram.
struct Channel {
  std::string content;           // "DIST1", "DIST2", "RSSI1", ...
  float scale_factor = 1.0f;     // value * scale_factor + scale_offset
  float scale_offset = 0.0f;
  std::int32_t start_angle_1e4deg = 0;  // angle of the first value, 1/10000 deg
  std::uint16_t angular_step_1e4deg = 0;
  std::vector<std::uint16_t> data;      // raw values (8-bit channels widened)
};

struct DeviceDateTime {
  std::uint16_t year = 0;
  std::uint8_t month = 0, day = 0, hour = 0, minute = 0, second = 0;
  std::uint32_t microsecond = 0;
};

// The content of an sRA/sSN LMDscandata telegram, field by field.
struct ScanData {
  std::uint16_t version = 1;
  std::uint16_t device_number = 0;
  std::uint32_t serial_number = 0;
  std::uint8_t device_status[2] = {0, 0};     // "0 0" = ok
  std::uint16_t telegram_counter = 0;
  std::uint16_t scan_counter = 0;
  std::uint32_t time_since_startup_us = 0;    // device clock at the scan's zero index
  std::uint32_t time_of_transmission_us = 0;  // device clock when the scan was handed to output
  std::uint8_t digital_inputs[2] = {0, 0};
  std::uint8_t digital_outputs[2] = {0, 0};
  std::uint16_t reserved = 0;
  std::uint32_t scan_frequency_centihz = 0;   // 1/100 Hz
  std::uint32_t measurement_frequency_100hz = 0;  // inverse time between two shots, in 100 Hz
  struct Encoder {
    std::uint32_t position = 0;
    std::uint16_t speed = 0;
  };
  std::vector<Encoder> encoders;
  std::vector<Channel> channels16;  // DIST1, and RSSI1 when configured 16 bit
  std::vector<Channel> channels8;   // RSSI1 when configured 8 bit
  bool has_position = false;
  float position[6] = {0, 0, 0, 0, 0, 0};  // x y z, rot x y z
  std::uint8_t rotation_type = 0;
  std::string device_name;          // empty when not transmitted
  std::string comment;
  std::optional<DeviceDateTime> date_time;
  std::string event_type;           // empty when no event block

  // The first channel (16- or 8-bit) whose content is `content`, or nullptr.
  const Channel* find_channel(std::string_view content) const;
};

// Parses the arguments of an LMDscandata telegram. Every field is checked:
// numbers must be valid hex of their width, counts must match the data
// present and stay below the limits, and nothing may be left over.
std::variant<ScanData, ParseError> parse_scan_data(const Telegram& telegram);

// The lens contamination level an "sRA LCMstate" answer carries (an enum8,
// as SICK's telegram listing has it), or nullopt for any other telegram or
// a value out of range.
enum class ContaminationLevel : std::uint8_t { kNone = 0, kWarning = 1, kError = 2, kSeriousError = 3 };
std::optional<ContaminationLevel> contamination_level(const Telegram& telegram);

// DIST values below this are not distances (SICK: 0 = no echo, 1 = dazzled, 2..15 reserved).
inline constexpr std::uint16_t kFirstValidDistance = 16;

// Distances of a DIST channel in metres: value * scale * 1 mm + offset;
// reserved values (< kFirstValidDistance) become NaN ("no return").
std::vector<float> distances_m(const Channel& channel);

// Hard limits against absurd telegrams.
inline constexpr std::size_t kMaxChannelValues = 10000;
inline constexpr std::size_t kMaxChannels = 8;
inline constexpr std::size_t kMaxEncoders = 8;

// ----------------------------------------------------------- stream parser --

// What a byte stream from the sensor turns into.
struct ScanEvent {
  ScanData scan;
};
struct ReplyEvent {
  Telegram telegram;  // any answer that is not scan data (sAN, sWA, sEA, sFA, ...)
};
struct ErrorEvent {
  std::string message;  // a telegram that did not parse (counted, skipped)
};
using StreamEvent = std::variant<ScanEvent, ReplyEvent, ErrorEvent>;

// Framer + parser: bytes in, events out. Keeps state across calls.
class StreamParser {
 public:
  struct Counters {
    std::uint64_t scans = 0;
    std::uint64_t replies = 0;
    std::uint64_t malformed = 0;   // framed telegrams that failed to parse
  };
  StreamParser() = default;
  explicit StreamParser(Framer::Options options) : framer_(options) {}

  std::vector<StreamEvent> push(std::string_view bytes);
  void reset() { framer_.reset(); }
  const Counters& counters() const { return counters_; }
  const Framer::Counters& framer_counters() const { return framer_.counters(); }

 private:
  Framer framer_;
  Counters counters_;
};

// ------------------------------------------------------------- sensor side --

// Encodes "sSN LMDscandata ..." (or "sRA" when `as_poll_answer`) framed with
// STX/ETX, the exact inverse of parse_scan_data for every field it supports.
std::string encode_scan_data(const ScanData& scan, bool as_poll_answer = false);

// Encodes an answer telegram "<type> <name> <args...>" framed with STX/ETX.
std::string encode_reply(std::string_view type, std::string_view name,
                         const std::vector<std::string>& args = {});

// CoLa-A integers for the encoder, the request builders and the simulator's
// replies: upper-case hex without leading zeros; an int32 as its two's complement.
std::string hex(std::uint32_t value);
std::string hex_int32(std::int32_t value);

}  // namespace pex::cola

namespace pex::cola {

// Maps the sensor's microsecond counter (uint32, wraps every ~71.6 min) to
// host time. The counter is unwrapped; the offset host - device is estimated
// as the tenth-percentile of (host receive time - device transmission time)
// over the last `window` scans: transport delay only ever adds to it, so the
// smallest samples are the truest, and the percentile (not the minimum) lets
// a few samples taken with a receive clock that was behind go by.
//
// A sample further than `max_step_us` from the estimate is an outlier and
// leaves the estimate alone: after a stall of the reader (a loaded computer,
// a network hiccup) the telegrams that waited are read at once, at one
// receive time, and starting the estimate afresh on them stamped every one
// of them with that time — a second of scans placed at the pose of its end.
// Only a run of outliers that agree with each other (within max_step_us) for
// `new_offset_after_us` of device time is a new offset (the host clock
// stepped): the estimate starts afresh on that run. Until the window holds
// `settled_samples` there are no outliers: the first telegrams of a
// connection may have waited too, and the smallest sample is the truest. A
// restarted sensor is a new connection, and the reader calls reset().
class DeviceClock {
 public:
  struct Options {
    std::size_t window = 250;                   // scans (10 s at 25 Hz)
    std::int64_t max_step_us = 500'000;
    std::int64_t new_offset_after_us = 1'000'000;  // device time
    std::size_t settled_samples = 25;              // scans (1 s at 25 Hz)
  };
  DeviceClock() = default;
  explicit DeviceClock(Options options) : options_(options) {}

  struct Mapped {
    std::int64_t device_us;   // unwrapped device time of the scan (time since start-up)
    std::int64_t host_us;     // that instant in host time
  };
  Mapped map(std::uint32_t scan_device_us, std::uint32_t transmit_device_us, std::int64_t host_receive_us);
  void reset();
  // New offsets taken (the estimate started afresh on a run of outliers).
  std::uint64_t resets() const { return resets_; }
  // Samples further than max_step_us from the estimate, all told.
  std::uint64_t outliers() const { return outliers_; }

 private:
  struct Sample {
    std::int64_t transmit_us;  // unwrapped device time
    std::int64_t offset_us;    // host receive - transmit
  };
  std::int64_t unwrap(std::uint32_t raw);
  std::int64_t robust_minimum() const;

  Options options_;
  bool have_last_ = false;
  std::uint32_t last_raw_ = 0;
  std::int64_t wraps_ = 0;
  std::vector<std::int64_t> offsets_;  // ring of recent samples
  std::size_t next_ = 0;
  std::vector<Sample> outlier_run_;    // the outliers since the last sample that agreed with the estimate
  std::uint64_t resets_ = 0;
  std::uint64_t outliers_ = 0;
};

}  // namespace pex::cola
