#pragma once
// CANopen (CiA 301) and the CiA 402 drive profile, the subset a differential
// base needs in profile velocity mode. Pure logic over `struct can_frame`
// values: frames in, frames out, time passed in (microseconds, any epoch).
// docs/can.md lists every frame with its COB-ID and byte layout.
//
//   NMT           0x000         [command, node]       master -> nodes
//   SYNC          0x080         (empty)               master -> nodes, triggers TPDO1
//   EMCY          0x080 + node  [code lo, code hi, error register, 5 x 0]
//   TPDO1         0x180 + node  [statusword u16, position actual i32]   (sync, type 1)
//   RPDO1         0x200 + node  [controlword u16, target velocity i32]
//   SDO response  0x580 + node  expedited only
//   SDO request   0x600 + node  expedited only
//   heartbeat     0x700 + node  [NMT state]
// All multi-byte values little-endian, as CANopen requires.
#include <linux/can.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace pex::canopen {

using Frame = struct can_frame;

inline constexpr std::uint32_t kCobNmt = 0x000;
inline constexpr std::uint32_t kCobSync = 0x080;
inline constexpr std::uint32_t kCobEmcy = 0x080;
inline constexpr std::uint32_t kCobTpdo1 = 0x180;
inline constexpr std::uint32_t kCobRpdo1 = 0x200;
inline constexpr std::uint32_t kCobSdoTx = 0x580;  // node -> master
inline constexpr std::uint32_t kCobSdoRx = 0x600;  // master -> node
inline constexpr std::uint32_t kCobHeartbeat = 0x700;

// NMT commands (CiA 301).
enum class NmtCommand : std::uint8_t {
  kStart = 0x01,
  kStop = 0x02,
  kEnterPreOperational = 0x80,
  kResetNode = 0x81,
  kResetCommunication = 0x82,
};
// NMT states as reported in the heartbeat.
enum class NmtState : std::uint8_t {
  kBootUp = 0x00,
  kStopped = 0x04,
  kOperational = 0x05,
  kPreOperational = 0x7F,
};

// Object dictionary entries we use.
inline constexpr std::uint16_t kObjConsumerHeartbeatTime = 0x1016;  // sub 1: (producer node << 16) | ms
inline constexpr std::uint16_t kObjAbortConnectionOption = 0x6007;  // INT16: reaction to a lost master
inline constexpr std::uint16_t kObjQuickStopDeceleration = 0x6085;  // UINT32, velocity units per second
inline constexpr std::uint16_t kEmcyHeartbeatError = 0x8130;        // life guard / heartbeat error
// 0x6007 values (CiA 402).
enum class AbortConnectionOption : std::int16_t { kNone = 0, kFault = 1, kDisableVoltage = 2, kQuickStop = 3 };
inline constexpr std::uint16_t kObjControlword = 0x6040;
inline constexpr std::uint16_t kObjStatusword = 0x6041;
inline constexpr std::uint16_t kObjModesOfOperation = 0x6060;
inline constexpr std::uint16_t kObjModesOfOperationDisplay = 0x6061;
inline constexpr std::uint16_t kObjPositionActual = 0x6064;
inline constexpr std::uint16_t kObjTargetVelocity = 0x60FF;
inline constexpr std::int8_t kModeProfileVelocity = 3;

// CiA 402 power state machine states, decoded from the statusword.
enum class DriveState {
  kNotReadyToSwitchOn,
  kSwitchOnDisabled,
  kReadyToSwitchOn,
  kSwitchedOn,
  kOperationEnabled,
  kQuickStopActive,
  kFaultReactionActive,
  kFault,
};
const char* to_string(DriveState state);
DriveState decode_statusword(std::uint16_t statusword);

// Controlword commands (CiA 402 device control).
inline constexpr std::uint16_t kCwDisableVoltage = 0x0000;
inline constexpr std::uint16_t kCwQuickStop = 0x0002;
inline constexpr std::uint16_t kCwShutdown = 0x0006;
inline constexpr std::uint16_t kCwSwitchOn = 0x0007;
inline constexpr std::uint16_t kCwEnableOperation = 0x000F;
inline constexpr std::uint16_t kCwFaultReset = 0x0080;  // acts on the rising edge of bit 7

// Frame builders and readers. A reader returns nullopt for a frame of the
// wrong id or length, or with RTR/error/extended flags: malformed input is
// rejected here, once.
Frame make_frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes);
Frame nmt_frame(NmtCommand command, std::uint8_t node_id);  // node 0 = all nodes
Frame sync_frame();
Frame heartbeat_frame(std::uint8_t node_id, NmtState state);
Frame rpdo1_frame(std::uint8_t node_id, std::uint16_t controlword, std::int32_t target_velocity);
Frame tpdo1_frame(std::uint8_t node_id, std::uint16_t statusword, std::int32_t position_actual);
Frame emcy_frame(std::uint8_t node_id, std::uint16_t error_code, std::uint8_t error_register);
// Expedited SDO download (write) of up to 4 bytes, and its answers.
Frame sdo_write_frame(std::uint8_t node_id, std::uint16_t index, std::uint8_t subindex,
                      std::uint32_t value, std::uint8_t size_bytes);
Frame sdo_write_ack_frame(std::uint8_t node_id, std::uint16_t index, std::uint8_t subindex);
Frame sdo_abort_frame(std::uint8_t node_id, std::uint16_t index, std::uint8_t subindex,
                      std::uint32_t abort_code);

bool is_plain_data_frame(const Frame& frame);  // standard 11-bit id, no RTR, no error flag
std::uint8_t node_of(const Frame& frame);      // id & 0x7F
std::uint32_t function_of(const Frame& frame);  // id & 0x780

struct Rpdo1 {
  std::uint16_t controlword;
  std::int32_t target_velocity;
};
struct Tpdo1 {
  std::uint16_t statusword;
  std::int32_t position_actual;
};
struct SdoRequest {
  std::uint8_t command;   // 0x2F/0x2B/0x27/0x23 expedited download of 1/2/3/4 bytes
  std::uint16_t index;
  std::uint8_t subindex;
  std::uint32_t value;
};
struct SdoResponse {
  bool abort;                 // true: abort with abort_code, false: download acknowledged
  std::uint16_t index;
  std::uint8_t subindex;
  std::uint32_t abort_code;
};
std::optional<Rpdo1> read_rpdo1(const Frame& frame);
std::optional<Tpdo1> read_tpdo1(const Frame& frame);
std::optional<SdoRequest> read_sdo_request(const Frame& frame);
std::optional<SdoResponse> read_sdo_response(const Frame& frame);
std::optional<NmtState> read_heartbeat(const Frame& frame);

// ------------------------------------------------------------------ master --

// Keeps a set of CiA 402 drives in profile velocity mode, Operation Enabled:
// configures each by SDO (mode 0x6060 = 3; the drive-side watchdog: consumer
// heartbeat time 0x1016:01 on our heartbeat, abort connection option 0x6007,
// quick stop deceleration 0x6085), starts it (NMT), walks its state machine
// with the controlword, resets faults, watches its heartbeat, produces its own
// heartbeat, and sends the target velocities. Call handle() for every received
// frame and step() at the control rate; step() returns the frames to send.
//
// Why the drive-side watchdog: a master that dies (kill -9, a crash, a cut
// cable) sends nothing more, and a drive left alone keeps its last target
// velocity for ever. With 0x1016 the drive itself notices our heartbeat is
// gone and stops the wheels (0x6007 = quick stop), whatever became of us.
// Every (re)configuration writes it again: a restarted master re-arms it.
class Cia402Master {
 public:
  struct Options {
    std::vector<std::uint8_t> node_ids = {1, 2};
    std::int64_t heartbeat_timeout_us = 300'000;  // missed heartbeat after this long
    std::int64_t sdo_timeout_us = 200'000;        // retry configuration after this long
    std::int64_t fault_reset_period_us = 100'000; // between fault-reset edges
    // Our own heartbeat (COB-ID 0x700 + master_node_id) every this long;
    // 0 = none (and then no drive watchdog either).
    std::uint8_t master_node_id = 0x7F;
    std::int64_t master_heartbeat_period_us = 50'000;
    // Written to each drive's 0x1016:01: it reacts (0x6007) when our heartbeat
    // is missing this long. 0 = the drive watchdog is not configured.
    std::int64_t drive_heartbeat_consumer_us = 150'000;
    AbortConnectionOption abort_option = AbortConnectionOption::kQuickStop;
    std::uint32_t quick_stop_deceleration = 0;  // 0x6085, velocity units/s; 0 = leave the drive's
  };
  // One expedited SDO write of the configuration.
  struct ConfigWrite {
    std::uint16_t index;
    std::uint8_t subindex;
    std::uint32_t value;
    std::uint8_t size_bytes;
  };

  enum class Phase {
    kUnknown,        // never heard of it / lost: waiting for a heartbeat
    kConfiguring,    // SDO write of the mode in flight
    kStarting,       // NMT start sent, waiting for heartbeat Operational
    kEnabling,       // walking the CiA 402 state machine
    kReady,          // Operation Enabled: target velocity is applied
  };

  struct NodeStatus {
    std::uint8_t node_id = 0;
    Phase phase = Phase::kUnknown;
    std::size_t config_step = 0;     // kConfiguring: index into configuration()
    NmtState nmt_state = NmtState::kBootUp;
    bool heartbeat_seen = false;
    bool heartbeat_lost = false;     // no heartbeat within heartbeat_timeout_us
    std::int64_t last_heartbeat_us = 0;
    std::uint16_t statusword = 0;
    bool statusword_seen = false;
    DriveState drive_state = DriveState::kNotReadyToSwitchOn;
    std::int32_t position_actual = 0;
    bool position_seen = false;
    std::int64_t position_time_us = 0;  // when position_actual was received
    std::uint16_t last_emcy_code = 0;
    std::uint64_t faults = 0;            // entries into Fault
    std::uint64_t heartbeat_losses = 0;
    std::uint64_t emcy_count = 0;
    std::uint64_t restarts = 0;          // boot-ups seen after the first
    std::int64_t phase_since_us = 0;
    bool fault_reset_high = false;
    std::int64_t fault_reset_edge_us = 0;
  };

  struct Counters {
    std::uint64_t frames_in = 0;
    std::uint64_t frames_ignored = 0;    // not for us
    std::uint64_t frames_malformed = 0;  // ours, but wrong length/flags
    std::uint64_t sdo_aborts = 0;
  };

  explicit Cia402Master(Options options);

  void handle(const Frame& frame, std::int64_t now_us);
  // Frames for this control period. target_velocity[i] is for node_ids[i] in
  // the drive's velocity units; it is sent only to nodes in kReady, others get 0.
  std::vector<Frame> step(std::int64_t now_us, const std::vector<std::int32_t>& target_velocity);

  // True when every node is Operation Enabled with a live heartbeat.
  bool all_ready() const;
  const std::vector<NodeStatus>& nodes() const { return nodes_; }
  const Counters& counters() const { return counters_; }
  const Options& options() const { return options_; }
  // The SDO writes every drive gets before it is started, in order.
  const std::vector<ConfigWrite>& configuration() const { return configuration_; }

 private:
  NodeStatus* find(std::uint8_t node_id);
  void set_phase(NodeStatus& node, Phase phase, std::int64_t now_us);

  Options options_;
  std::vector<NodeStatus> nodes_;
  Counters counters_;
  std::vector<bool> request_pending_;  // per node: SDO write or NMT start sent, awaiting its effect
  std::vector<ConfigWrite> configuration_;
  std::int64_t next_master_heartbeat_us_ = 0;  // 0: at the first step
};
const char* to_string(Cia402Master::Phase phase);

// ------------------------------------------------------------- drive node --

// A simulated CiA 402 drive with an encoder, for the simulator and tests. It
// follows the NMT and CiA 402 state machines, accepts SDO writes of the mode,
// the consumer heartbeat time (0x1016:01), the abort connection option
// (0x6007) and the quick stop deceleration (0x6085), answers SYNC with TPDO1
// when Operational, applies RPDO1, produces a heartbeat, and ramps its actual
// velocity to the target within its acceleration limit when Operation Enabled
// (to zero otherwise; in Quick Stop Active at the quick stop deceleration,
// then Switch On Disabled, quick stop option code 2).
//
// Heartbeat consumer as CiA 301 has it: armed by the first heartbeat of the
// configured producer; when none follows within the consumer time, a
// heartbeat event: EMCY 0x8130 and the 0x6007 reaction (kNone: nothing,
// kFault: Fault, kDisableVoltage: Switch On Disabled, the motor coasting down,
// kQuickStop: Quick Stop Active). The NMT state is kept (0x1029 = 1). The next
// heartbeat re-arms it.
class DriveNode {
 public:
  struct Options {
    std::uint8_t node_id = 1;
    std::int64_t heartbeat_period_us = 100'000;
    double max_acceleration = 200'000.0;   // velocity units per second (counts/s^2)
    double quick_stop_deceleration = 200'000.0;  // until 0x6085 is written
  };

  explicit DriveNode(Options options);

  // Reacts to one received frame; returns the answers (SDO, TPDO).
  std::vector<Frame> handle(const Frame& frame);
  // Advances the motor to now_us and returns due frames (heartbeat).
  std::vector<Frame> step(std::int64_t now_us);

  // Forces the drive into Fault (as a real drive does on over-current) and
  // returns the EMCY frame it sends.
  Frame inject_fault(std::uint16_t error_code);
  // Power cycle: back to boot-up (the next step() sends the boot-up message).
  void power_cycle();
  // Silences the node (heartbeat and all answers), as a cut cable would.
  void set_silent(bool silent) { silent_ = silent; }

  double velocity_actual() const { return velocity_; }  // counts/s
  double position_actual() const { return position_; }  // counts
  std::int32_t target_velocity() const { return target_velocity_; }
  DriveState state() const { return state_; }
  NmtState nmt_state() const { return nmt_; }
  std::uint16_t statusword() const;
  std::int8_t mode() const { return mode_; }
  std::uint8_t node_id() const { return options_.node_id; }
  std::int64_t consumer_heartbeat_time_us() const { return consumer_time_us_; }
  AbortConnectionOption abort_option() const { return abort_option_; }
  std::uint64_t heartbeat_events() const { return heartbeat_events_; }
  // Whether `frame` is a heartbeat of the producer this drive's watchdog
  // consumes (0x1016:01 set).
  bool consumes(const Frame& frame) const;
  // The heartbeat watchdog's deadline: a step() later than this raises the
  // heartbeat event unless a heartbeat of its producer comes first. nullopt
  // while it cannot fire (not armed, a heartbeat waiting for the next step)
  // or must not be waited for (the node silenced, or booting: it hears
  // nothing before its next step). The simulator holds its clock here while
  // the producer is alive (sim/pacer.hpp).
  std::optional<std::int64_t> heartbeat_deadline_us() const;

 private:
  void apply_controlword(std::uint16_t controlword);
  std::optional<std::uint32_t> sdo_abort_code_for(const SdoRequest& request);

  Options options_;
  NmtState nmt_ = NmtState::kBootUp;
  bool boot_up_pending_ = true;
  DriveState state_ = DriveState::kSwitchOnDisabled;
  std::int8_t mode_ = 0;
  std::uint16_t last_controlword_ = 0;
  std::int32_t target_velocity_ = 0;
  double velocity_ = 0.0;
  double position_ = 0.0;
  std::optional<std::int64_t> last_step_us_;
  std::int64_t next_heartbeat_us_ = 0;
  bool silent_ = false;
  // Heartbeat consumer (0x1016:01) and its reaction (0x6007).
  std::int64_t consumer_time_us_ = 0;  // 0: off
  std::uint8_t consumer_node_ = 0;
  AbortConnectionOption abort_option_ = AbortConnectionOption::kFault;  // CiA 402's default
  double quick_stop_deceleration_ = 0.0;
  bool producer_heard_ = false;        // a heartbeat came since the last step
  bool consumer_armed_ = false;
  std::int64_t producer_heard_us_ = 0;
  std::uint64_t heartbeat_events_ = 0;
};

}  // namespace pex::canopen
