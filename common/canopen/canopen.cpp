#include "canopen/canopen.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace pex::canopen {

const char* to_string(DriveState state) {
  switch (state) {
    case DriveState::kNotReadyToSwitchOn: return "not_ready_to_switch_on";
    case DriveState::kSwitchOnDisabled: return "switch_on_disabled";
    case DriveState::kReadyToSwitchOn: return "ready_to_switch_on";
    case DriveState::kSwitchedOn: return "switched_on";
    case DriveState::kOperationEnabled: return "operation_enabled";
    case DriveState::kQuickStopActive: return "quick_stop_active";
    case DriveState::kFaultReactionActive: return "fault_reaction_active";
    case DriveState::kFault: return "fault";
  }
  return "?";
}

const char* to_string(Cia402Master::Phase phase) {
  switch (phase) {
    case Cia402Master::Phase::kUnknown: return "unknown";
    case Cia402Master::Phase::kConfiguring: return "configuring";
    case Cia402Master::Phase::kStarting: return "starting";
    case Cia402Master::Phase::kEnabling: return "enabling";
    case Cia402Master::Phase::kReady: return "ready";
  }
  return "?";
}

DriveState decode_statusword(std::uint16_t sw) {
  // Bit patterns of CiA 402 (x = don't care), bits 6 5 3 2 1 0.
  if ((sw & 0x4F) == 0x40) return DriveState::kSwitchOnDisabled;
  if ((sw & 0x6F) == 0x21) return DriveState::kReadyToSwitchOn;
  if ((sw & 0x6F) == 0x23) return DriveState::kSwitchedOn;
  if ((sw & 0x6F) == 0x27) return DriveState::kOperationEnabled;
  if ((sw & 0x6F) == 0x07) return DriveState::kQuickStopActive;
  if ((sw & 0x4F) == 0x0F) return DriveState::kFaultReactionActive;
  if ((sw & 0x4F) == 0x08) return DriveState::kFault;
  return DriveState::kNotReadyToSwitchOn;
}

namespace {

void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint16_t get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t get_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

Frame empty_frame(std::uint32_t id, std::uint8_t dlc) {
  Frame f;
  std::memset(&f, 0, sizeof f);
  f.can_id = id;
  f.can_dlc = dlc;
  return f;
}

bool is_valid_nmt_state(std::uint8_t s) {
  return s == 0x00 || s == 0x04 || s == 0x05 || s == 0x7F;
}

}  // namespace

Frame make_frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  Frame f = empty_frame(id, static_cast<std::uint8_t>(std::min<std::size_t>(bytes.size(), 8)));
  std::size_t i = 0;
  for (std::uint8_t b : bytes) {
    if (i >= 8) break;
    f.data[i++] = b;
  }
  return f;
}

Frame nmt_frame(NmtCommand command, std::uint8_t node_id) {
  return make_frame(kCobNmt, {static_cast<std::uint8_t>(command), node_id});
}
Frame sync_frame() { return empty_frame(kCobSync, 0); }
Frame heartbeat_frame(std::uint8_t node_id, NmtState state) {
  return make_frame(kCobHeartbeat + node_id, {static_cast<std::uint8_t>(state)});
}
Frame rpdo1_frame(std::uint8_t node_id, std::uint16_t controlword, std::int32_t target_velocity) {
  Frame f = empty_frame(kCobRpdo1 + node_id, 6);
  put_u16(f.data, controlword);
  put_u32(f.data + 2, static_cast<std::uint32_t>(target_velocity));
  return f;
}
Frame tpdo1_frame(std::uint8_t node_id, std::uint16_t statusword, std::int32_t position_actual) {
  Frame f = empty_frame(kCobTpdo1 + node_id, 6);
  put_u16(f.data, statusword);
  put_u32(f.data + 2, static_cast<std::uint32_t>(position_actual));
  return f;
}
Frame emcy_frame(std::uint8_t node_id, std::uint16_t error_code, std::uint8_t error_register) {
  Frame f = empty_frame(kCobEmcy + node_id, 8);
  put_u16(f.data, error_code);
  f.data[2] = error_register;
  return f;
}
Frame sdo_write_frame(std::uint8_t node_id, std::uint16_t index, std::uint8_t subindex,
                      std::uint32_t value, std::uint8_t size_bytes) {
  size_bytes = std::clamp<std::uint8_t>(size_bytes, 1, 4);
  Frame f = empty_frame(kCobSdoRx + node_id, 8);
  // ccs = 1 (download), e = 1, s = 1, n = 4 - size
  f.data[0] = static_cast<std::uint8_t>(0x23 | ((4 - size_bytes) << 2));
  put_u16(f.data + 1, index);
  f.data[3] = subindex;
  put_u32(f.data + 4, value);
  return f;
}
Frame sdo_write_ack_frame(std::uint8_t node_id, std::uint16_t index, std::uint8_t subindex) {
  Frame f = empty_frame(kCobSdoTx + node_id, 8);
  f.data[0] = 0x60;
  put_u16(f.data + 1, index);
  f.data[3] = subindex;
  return f;
}
Frame sdo_abort_frame(std::uint8_t node_id, std::uint16_t index, std::uint8_t subindex,
                      std::uint32_t abort_code) {
  Frame f = empty_frame(kCobSdoTx + node_id, 8);
  f.data[0] = 0x80;
  put_u16(f.data + 1, index);
  f.data[3] = subindex;
  put_u32(f.data + 4, abort_code);
  return f;
}

bool is_plain_data_frame(const Frame& f) {
  return (f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) == 0 && f.can_dlc <= 8;
}
std::uint8_t node_of(const Frame& f) { return static_cast<std::uint8_t>(f.can_id & 0x7F); }
std::uint32_t function_of(const Frame& f) { return f.can_id & 0x780; }

std::optional<Rpdo1> read_rpdo1(const Frame& f) {
  if (!is_plain_data_frame(f) || function_of(f) != kCobRpdo1 || f.can_dlc != 6) return std::nullopt;
  return Rpdo1{get_u16(f.data), static_cast<std::int32_t>(get_u32(f.data + 2))};
}
std::optional<Tpdo1> read_tpdo1(const Frame& f) {
  if (!is_plain_data_frame(f) || function_of(f) != kCobTpdo1 || f.can_dlc != 6) return std::nullopt;
  return Tpdo1{get_u16(f.data), static_cast<std::int32_t>(get_u32(f.data + 2))};
}
std::optional<SdoRequest> read_sdo_request(const Frame& f) {
  if (!is_plain_data_frame(f) || function_of(f) != kCobSdoRx || f.can_dlc != 8) return std::nullopt;
  return SdoRequest{f.data[0], get_u16(f.data + 1), f.data[3], get_u32(f.data + 4)};
}
std::optional<SdoResponse> read_sdo_response(const Frame& f) {
  if (!is_plain_data_frame(f) || function_of(f) != kCobSdoTx || f.can_dlc != 8) return std::nullopt;
  if (f.data[0] == 0x60) return SdoResponse{false, get_u16(f.data + 1), f.data[3], 0};
  if (f.data[0] == 0x80) return SdoResponse{true, get_u16(f.data + 1), f.data[3], get_u32(f.data + 4)};
  return std::nullopt;
}
std::optional<NmtState> read_heartbeat(const Frame& f) {
  if (!is_plain_data_frame(f) || function_of(f) != kCobHeartbeat || f.can_dlc != 1) return std::nullopt;
  if (!is_valid_nmt_state(f.data[0])) return std::nullopt;
  return static_cast<NmtState>(f.data[0]);
}

// ------------------------------------------------------------------ master --

Cia402Master::Cia402Master(Options options) : options_(std::move(options)) {
  for (std::uint8_t id : options_.node_ids) {
    NodeStatus n;
    n.node_id = id;
    nodes_.push_back(n);
  }
  request_pending_.assign(nodes_.size(), false);
  configuration_.push_back({kObjModesOfOperation, 0, static_cast<std::uint8_t>(kModeProfileVelocity), 1});
  if (options_.quick_stop_deceleration > 0)
    configuration_.push_back({kObjQuickStopDeceleration, 0, options_.quick_stop_deceleration, 4});
  if (options_.drive_heartbeat_consumer_us > 0 && options_.master_heartbeat_period_us > 0) {
    const auto ms = static_cast<std::uint32_t>(std::min<std::int64_t>(0xFFFF, options_.drive_heartbeat_consumer_us / 1000));
    configuration_.push_back({kObjAbortConnectionOption, 0,
                              static_cast<std::uint16_t>(static_cast<std::int16_t>(options_.abort_option)), 2});
    configuration_.push_back(
        {kObjConsumerHeartbeatTime, 1, (std::uint32_t{options_.master_node_id} << 16) | ms, 4});
  }
}

Cia402Master::NodeStatus* Cia402Master::find(std::uint8_t node_id) {
  for (auto& n : nodes_) {
    if (n.node_id == node_id) return &n;
  }
  return nullptr;
}

void Cia402Master::set_phase(NodeStatus& node, Phase phase, std::int64_t now_us) {
  if (node.phase == phase) return;
  node.phase = phase;
  node.phase_since_us = now_us;
  if (phase == Phase::kConfiguring) node.config_step = 0;
  request_pending_[static_cast<std::size_t>(&node - nodes_.data())] = false;
}

void Cia402Master::handle(const Frame& frame, std::int64_t now_us) {
  ++counters_.frames_in;
  if (!is_plain_data_frame(frame)) {
    ++counters_.frames_ignored;  // error frames are the transport user's business
    return;
  }
  const std::uint32_t function = function_of(frame);
  const std::uint8_t id = node_of(frame);
  NodeStatus* node = id == 0 ? nullptr : find(id);
  if (!node || function == kCobRpdo1 || function == kCobSdoRx || function == kCobNmt) {
    ++counters_.frames_ignored;
    return;
  }
  switch (function) {
    case kCobHeartbeat: {
      auto state = read_heartbeat(frame);
      if (!state) break;
      if (*state == NmtState::kBootUp && node->heartbeat_seen) ++node->restarts;
      // Out of NMT Stopped (our "enter pre-operational" worked): configure at once.
      if (node->phase == Phase::kConfiguring && node->nmt_state == NmtState::kStopped && *state != NmtState::kStopped)
        request_pending_[static_cast<std::size_t>(node - nodes_.data())] = false;
      node->heartbeat_seen = true;
      node->heartbeat_lost = false;
      node->last_heartbeat_us = now_us;
      node->nmt_state = *state;
      const bool operational = *state == NmtState::kOperational;
      if (*state == NmtState::kBootUp || node->phase == Phase::kUnknown) {
        // Configured from the start even when already Operational (a restarted
        // master finds its drives running): the watchdog is ours to set.
        set_phase(*node, Phase::kConfiguring, now_us);
        if (*state == NmtState::kBootUp) {
          // A restarted drive's encoder counts from zero again: the position
          // from before is not a reading of the new counter. Until its first
          // new TPDO the odometry has no position of it (a stale one became
          // the new baseline and the robot jumped back 5 cm: the sanitizer
          // run's Hardware.DriverStopsOnBusErrors..., 1 run in 3).
          node->statusword_seen = false;
          node->position_seen = false;
        }
      } else if (node->phase == Phase::kStarting && operational) {
        set_phase(*node, Phase::kEnabling, now_us);
      } else if ((node->phase == Phase::kEnabling || node->phase == Phase::kReady) && !operational) {
        set_phase(*node, Phase::kConfiguring, now_us);
      }
      return;
    }
    case kCobTpdo1: {
      auto pdo = read_tpdo1(frame);
      if (!pdo) break;
      const DriveState state = decode_statusword(pdo->statusword);
      if (state == DriveState::kFault && (!node->statusword_seen || node->drive_state != DriveState::kFault)) {
        ++node->faults;
      }
      node->statusword = pdo->statusword;
      node->statusword_seen = true;
      node->drive_state = state;
      node->position_actual = pdo->position_actual;
      node->position_seen = true;
      node->position_time_us = now_us;
      if (node->phase == Phase::kEnabling && state == DriveState::kOperationEnabled) {
        set_phase(*node, Phase::kReady, now_us);
      } else if (node->phase == Phase::kReady && state != DriveState::kOperationEnabled) {
        set_phase(*node, Phase::kEnabling, now_us);
      }
      return;
    }
    case kCobEmcy: {
      if (frame.can_dlc != 8) break;
      ++node->emcy_count;
      node->last_emcy_code = get_u16(frame.data);
      return;
    }
    case kCobSdoTx: {
      auto response = read_sdo_response(frame);
      if (!response) break;
      if (response->abort) {
        ++counters_.sdo_aborts;
        return;  // retried after sdo_timeout_us
      }
      if (node->phase == Phase::kConfiguring && node->config_step < configuration_.size() &&
          response->index == configuration_[node->config_step].index &&
          response->subindex == configuration_[node->config_step].subindex) {
        const auto i = static_cast<std::size_t>(node - nodes_.data());
        request_pending_[i] = false;  // the next write at the next step
        if (++node->config_step == configuration_.size())
          set_phase(*node, node->nmt_state == NmtState::kOperational ? Phase::kEnabling : Phase::kStarting, now_us);
      }
      return;
    }
    default:
      ++counters_.frames_ignored;
      return;
  }
  ++counters_.frames_malformed;
}

std::vector<Frame> Cia402Master::step(std::int64_t now_us, const std::vector<std::int32_t>& target_velocity) {
  std::vector<Frame> out;
  if (options_.master_heartbeat_period_us > 0 && now_us >= next_master_heartbeat_us_) {
    out.push_back(heartbeat_frame(options_.master_node_id, NmtState::kOperational));
    next_master_heartbeat_us_ = now_us + options_.master_heartbeat_period_us;
  }
  out.push_back(sync_frame());
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    NodeStatus& node = nodes_[i];
    if (node.phase_since_us == 0 && node.phase == Phase::kUnknown) node.phase_since_us = now_us;
    // Heartbeat consumer: a node silent for longer than the timeout is lost
    // until it is heard again; it is then configured from the start.
    const std::int64_t heard_us = node.heartbeat_seen ? node.last_heartbeat_us : node.phase_since_us;
    if (now_us - heard_us > options_.heartbeat_timeout_us) {
      if (!node.heartbeat_lost) {
        node.heartbeat_lost = true;
        if (node.heartbeat_seen) ++node.heartbeat_losses;
      }
      if (node.phase != Phase::kUnknown) set_phase(node, Phase::kUnknown, now_us);
    }
    const bool retry_due = now_us - node.phase_since_us > options_.sdo_timeout_us;
    switch (node.phase) {
      case Phase::kUnknown:
        break;
      case Phase::kConfiguring:
        if (node.nmt_state == NmtState::kStopped) {
          // An NMT stop (from a tool, another master): a stopped node answers
          // no SDO, so it goes to pre-operational first (CiA 301), then the
          // configuration and the start follow as after a boot-up.
          if (!request_pending_[i] || retry_due) {
            out.push_back(nmt_frame(NmtCommand::kEnterPreOperational, node.node_id));
            request_pending_[i] = true;
            node.phase_since_us = now_us;
          }
          break;
        }
        if (!request_pending_[i] || retry_due) {
          const ConfigWrite& w = configuration_[node.config_step];
          out.push_back(sdo_write_frame(node.node_id, w.index, w.subindex, w.value, w.size_bytes));
          request_pending_[i] = true;
          node.phase_since_us = now_us;
        }
        break;
      case Phase::kStarting:
        if (!request_pending_[i] || retry_due) {
          out.push_back(nmt_frame(NmtCommand::kStart, node.node_id));
          request_pending_[i] = true;
          node.phase_since_us = now_us;
        }
        break;
      case Phase::kEnabling: {
        std::uint16_t cw = kCwShutdown;
        if (node.statusword_seen) {
          switch (node.drive_state) {
            case DriveState::kFault:
              // Fault reset acts on a rising edge of bit 7: alternate low/high.
              if (now_us - node.fault_reset_edge_us >= options_.fault_reset_period_us) {
                node.fault_reset_high = !node.fault_reset_high;
                node.fault_reset_edge_us = now_us;
              }
              cw = node.fault_reset_high ? kCwFaultReset : kCwDisableVoltage;
              break;
            case DriveState::kFaultReactionActive:
            case DriveState::kQuickStopActive:
              cw = kCwDisableVoltage;
              break;
            case DriveState::kNotReadyToSwitchOn:
            case DriveState::kSwitchOnDisabled:
              cw = kCwShutdown;
              break;
            case DriveState::kReadyToSwitchOn:
              cw = kCwSwitchOn;
              break;
            case DriveState::kSwitchedOn:
            case DriveState::kOperationEnabled:
              cw = kCwEnableOperation;
              break;
          }
        }
        if (node.drive_state != DriveState::kFault) node.fault_reset_high = false;
        out.push_back(rpdo1_frame(node.node_id, cw, 0));
        break;
      }
      case Phase::kReady: {
        const std::int32_t v = i < target_velocity.size() ? target_velocity[i] : 0;
        out.push_back(rpdo1_frame(node.node_id, kCwEnableOperation, v));
        break;
      }
    }
  }
  return out;
}

bool Cia402Master::all_ready() const {
  return std::all_of(nodes_.begin(), nodes_.end(), [](const NodeStatus& n) {
    return n.phase == Phase::kReady && !n.heartbeat_lost;
  });
}

// ------------------------------------------------------------- drive node --

DriveNode::DriveNode(Options options)
    : options_(options), quick_stop_deceleration_(options.quick_stop_deceleration) {}

std::uint16_t DriveNode::statusword() const {
  std::uint16_t sw = 0;
  switch (state_) {
    case DriveState::kNotReadyToSwitchOn: sw = 0x0000; break;
    case DriveState::kSwitchOnDisabled: sw = 0x0040; break;
    case DriveState::kReadyToSwitchOn: sw = 0x0021; break;
    case DriveState::kSwitchedOn: sw = 0x0023; break;
    case DriveState::kOperationEnabled: sw = 0x0027; break;
    case DriveState::kQuickStopActive: sw = 0x0007; break;
    case DriveState::kFaultReactionActive: sw = 0x000F; break;
    case DriveState::kFault: sw = 0x0008; break;
  }
  return static_cast<std::uint16_t>(sw | 0x0200);  // bit 9: remote (controlled over the bus)
}

void DriveNode::apply_controlword(std::uint16_t cw) {
  const bool reset_edge = (cw & 0x80) && !(last_controlword_ & 0x80);
  last_controlword_ = cw;
  if (state_ == DriveState::kFault || state_ == DriveState::kFaultReactionActive) {
    if (reset_edge && state_ == DriveState::kFault) state_ = DriveState::kSwitchOnDisabled;
    return;
  }
  if (cw & 0x80) return;  // fault reset bit high outside Fault: no command
  const bool disable_voltage = (cw & 0x02) == 0;
  const bool quick_stop = (cw & 0x06) == 0x02;
  const bool shutdown = (cw & 0x07) == 0x06;
  const bool switch_on = (cw & 0x0F) == 0x07;
  const bool enable = (cw & 0x0F) == 0x0F;
  switch (state_) {
    case DriveState::kNotReadyToSwitchOn:
      break;
    case DriveState::kSwitchOnDisabled:
      if (shutdown) state_ = DriveState::kReadyToSwitchOn;
      break;
    case DriveState::kReadyToSwitchOn:
      if (switch_on) state_ = DriveState::kSwitchedOn;
      else if (disable_voltage || quick_stop) state_ = DriveState::kSwitchOnDisabled;
      break;
    case DriveState::kSwitchedOn:
      if (enable) state_ = DriveState::kOperationEnabled;
      else if (shutdown) state_ = DriveState::kReadyToSwitchOn;
      else if (disable_voltage || quick_stop) state_ = DriveState::kSwitchOnDisabled;
      break;
    case DriveState::kOperationEnabled:
      if (switch_on) state_ = DriveState::kSwitchedOn;
      else if (shutdown) state_ = DriveState::kReadyToSwitchOn;
      else if (disable_voltage) state_ = DriveState::kSwitchOnDisabled;
      else if (quick_stop) state_ = DriveState::kQuickStopActive;
      break;
    case DriveState::kQuickStopActive:
      if (enable) state_ = DriveState::kOperationEnabled;
      else if (disable_voltage) state_ = DriveState::kSwitchOnDisabled;
      break;
    case DriveState::kFaultReactionActive:
    case DriveState::kFault:
      break;
  }
}

std::vector<Frame> DriveNode::handle(const Frame& frame) {
  std::vector<Frame> out;
  if (silent_ || boot_up_pending_ || !is_plain_data_frame(frame)) return out;
  const std::uint32_t function = function_of(frame);
  const std::uint8_t id = node_of(frame);
  if (frame.can_id == kCobNmt) {
    if (frame.can_dlc != 2 || (frame.data[1] != 0 && frame.data[1] != options_.node_id)) return out;
    switch (static_cast<NmtCommand>(frame.data[0])) {
      case NmtCommand::kStart: nmt_ = NmtState::kOperational; break;
      case NmtCommand::kStop: nmt_ = NmtState::kStopped; break;
      case NmtCommand::kEnterPreOperational: nmt_ = NmtState::kPreOperational; break;
      case NmtCommand::kResetNode: power_cycle(); break;
      case NmtCommand::kResetCommunication:
        nmt_ = NmtState::kBootUp;
        boot_up_pending_ = true;
        break;
    }
    return out;
  }
  if (frame.can_id == kCobSync) {
    if (frame.can_dlc == 0 && nmt_ == NmtState::kOperational) {
      out.push_back(tpdo1_frame(options_.node_id, statusword(),
                                static_cast<std::int32_t>(std::llround(position_))));
    }
    return out;
  }
  if (consumes(frame)) {
    if (read_heartbeat(frame)) producer_heard_ = true;  // timed at the next step
    return out;
  }
  if (id != options_.node_id) return out;
  if (function == kCobRpdo1 && nmt_ == NmtState::kOperational) {
    auto pdo = read_rpdo1(frame);
    if (!pdo) return out;  // malformed: ignored, as a drive does
    target_velocity_ = pdo->target_velocity;
    apply_controlword(pdo->controlword);
    return out;
  }
  if (function == kCobSdoRx && (nmt_ == NmtState::kPreOperational || nmt_ == NmtState::kOperational)) {
    auto request = read_sdo_request(frame);
    if (!request) return out;
    const bool expedited_download = (request->command & 0xE3) == 0x23;
    if (!expedited_download) {
      out.push_back(sdo_abort_frame(options_.node_id, request->index, request->subindex,
                                    0x05040001));  // command specifier not valid
    } else if (const auto abort_code = sdo_abort_code_for(*request)) {
      out.push_back(sdo_abort_frame(options_.node_id, request->index, request->subindex, *abort_code));
    } else {
      out.push_back(sdo_write_ack_frame(options_.node_id, request->index, request->subindex));
    }
  }
  return out;
}

// The write's abort code, or nullopt when it was applied (the objects this
// drive has: 0x6060, 0x1016:01, 0x6007, 0x6085).
std::optional<std::uint32_t> DriveNode::sdo_abort_code_for(const SdoRequest& r) {
  constexpr std::uint32_t kNoObject = 0x06020000, kNoSubindex = 0x06090011, kRange = 0x06090030;
  switch (r.index) {
    case kObjModesOfOperation:
      if (r.subindex != 0) return kNoSubindex;
      if (static_cast<std::int8_t>(r.value & 0xFF) != kModeProfileVelocity) return kRange;
      mode_ = kModeProfileVelocity;
      return std::nullopt;
    case kObjConsumerHeartbeatTime:
      if (r.subindex != 1) return kNoSubindex;
      consumer_node_ = static_cast<std::uint8_t>((r.value >> 16) & 0x7F);
      consumer_time_us_ = 1000ll * static_cast<std::int64_t>(r.value & 0xFFFF);
      consumer_armed_ = false;  // armed again by the producer's next heartbeat
      producer_heard_ = false;
      return std::nullopt;
    case kObjAbortConnectionOption: {
      if (r.subindex != 0) return kNoSubindex;
      const auto v = static_cast<std::int16_t>(r.value & 0xFFFF);
      if (v < 0 || v > 3) return kRange;
      abort_option_ = static_cast<AbortConnectionOption>(v);
      return std::nullopt;
    }
    case kObjQuickStopDeceleration:
      if (r.subindex != 0) return kNoSubindex;
      if (r.value == 0) return kRange;
      quick_stop_deceleration_ = static_cast<double>(r.value);
      return std::nullopt;
    default:
      return kNoObject;
  }
}

std::vector<Frame> DriveNode::step(std::int64_t now_us) {
  std::vector<Frame> out;
  if (last_step_us_ && now_us > *last_step_us_) {
    const double dt = static_cast<double>(now_us - *last_step_us_) * 1e-6;
    const bool driving = state_ == DriveState::kOperationEnabled && nmt_ == NmtState::kOperational &&
                         mode_ == kModeProfileVelocity;
    const double goal = driving ? static_cast<double>(target_velocity_) : 0.0;
    const bool quick_stop = state_ == DriveState::kQuickStopActive;
    const double max_dv = (quick_stop ? quick_stop_deceleration_ : options_.max_acceleration) * dt;
    const double v0 = velocity_;
    velocity_ += std::clamp(goal - velocity_, -max_dv, max_dv);
    position_ += 0.5 * (v0 + velocity_) * dt;
    // Quick stop option code 2: once stopped, Switch On Disabled.
    if (quick_stop && velocity_ == 0.0) state_ = DriveState::kSwitchOnDisabled;
  }
  last_step_us_ = now_us;
  // Heartbeat consumer (CiA 301): armed by the producer's heartbeat; a
  // heartbeat event when the next one is later than the consumer time.
  if (producer_heard_) {
    producer_heard_ = false;
    consumer_armed_ = true;
    producer_heard_us_ = now_us;
  } else if (consumer_armed_ && consumer_time_us_ > 0 && now_us - producer_heard_us_ > consumer_time_us_) {
    consumer_armed_ = false;
    ++heartbeat_events_;
    if (!silent_) out.push_back(emcy_frame(options_.node_id, kEmcyHeartbeatError, 0x11));  // generic + communication
    if (state_ == DriveState::kOperationEnabled) {
      switch (abort_option_) {
        case AbortConnectionOption::kNone: break;
        case AbortConnectionOption::kFault: state_ = DriveState::kFault; break;
        case AbortConnectionOption::kDisableVoltage: state_ = DriveState::kSwitchOnDisabled; break;
        case AbortConnectionOption::kQuickStop: state_ = DriveState::kQuickStopActive; break;
      }
    }
  }
  if (silent_) return out;
  if (boot_up_pending_) {
    out.push_back(heartbeat_frame(options_.node_id, NmtState::kBootUp));
    boot_up_pending_ = false;
    nmt_ = NmtState::kPreOperational;
    next_heartbeat_us_ = now_us + options_.heartbeat_period_us;
    return out;
  }
  if (now_us >= next_heartbeat_us_) {
    out.push_back(heartbeat_frame(options_.node_id, nmt_));
    next_heartbeat_us_ += options_.heartbeat_period_us;
    if (next_heartbeat_us_ <= now_us) next_heartbeat_us_ = now_us + options_.heartbeat_period_us;
  }
  return out;
}

bool DriveNode::consumes(const Frame& frame) const {
  return consumer_time_us_ > 0 && is_plain_data_frame(frame) && function_of(frame) == kCobHeartbeat &&
         node_of(frame) == consumer_node_;
}

std::optional<std::int64_t> DriveNode::heartbeat_deadline_us() const {
  // Booting (after a reset of communication), the node hears nothing until
  // its next step: a clock held for its heartbeat would never get there.
  if (silent_ || boot_up_pending_ || producer_heard_ || !consumer_armed_ || consumer_time_us_ <= 0)
    return std::nullopt;
  return producer_heard_us_ + consumer_time_us_;
}

Frame DriveNode::inject_fault(std::uint16_t error_code) {
  state_ = DriveState::kFault;
  return emcy_frame(options_.node_id, error_code, 0x01);  // error register bit 0: generic error
}

void DriveNode::power_cycle() {
  nmt_ = NmtState::kBootUp;
  boot_up_pending_ = true;
  state_ = DriveState::kSwitchOnDisabled;
  mode_ = 0;
  target_velocity_ = 0;
  last_controlword_ = 0;
  consumer_time_us_ = 0;  // the object dictionary back to its defaults
  consumer_node_ = 0;
  consumer_armed_ = producer_heard_ = false;
  abort_option_ = AbortConnectionOption::kFault;
  quick_stop_deceleration_ = options_.quick_stop_deceleration;
  velocity_ = 0.0;
  position_ = 0.0;  // the encoder count restarts from zero, as on a real drive
}

}  // namespace pex::canopen
