// The TWINsync option card of one drive, bound to the drive's dictionary (so it lives above coe, next to
// the drive; the pure parts, telegram, mapping, link and parameters, are src/twinsync): it reads its
// configuration from the drive's dictionary (the parameters of src/device/twinsync_objects.cpp), checks it
// when it is written (refusing what cannot work, with the reason in 0x2102), builds the telegram from the
// send mapping once per control cycle, checks the received one (length, CRC) and copies its process data into
// the mapped parameters, runs the synchronisation controller of a slave and the monitoring of chapter 7.
//
// The drive calls receive() at the start of its control cycle and transmit() at its end. The port tells
// the drive the control word received from the master drive, whether the partner is enabled, and the
// error (40-xx, 39-xx) that is pending; the drive decides when it becomes a fault (in state Control).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "twinsync/errors.hpp"
#include "twinsync/link.hpp"
#include "twinsync/mapping.hpp"
#include "twinsync/status.hpp"
#include "twinsync/telegram.hpp"

namespace vecat::twinsync {

// LocalState, what the drive tells the port about itself every cycle: twinsync/status.hpp.

// (One cache line for what every run of the drive asks: the cable, the role and the end, first.)
class alignas(64) Port {
  public:
    Port(coe::ObjectDictionary& od, std::uint64_t period_ns);
    ~Port();

    // The cable: this card is end `end` (0 or 1) of the channel.
    void connect(std::shared_ptr<Channel> channel, int end);
    const std::shared_ptr<Channel>& channel() const { return channel_; }
    int end() const { return end_; }

    // The control cycle (the TWIN sampling time): one telegram each way per cycle.
    void set_period_ns(std::uint64_t ns) { period_ns_ = ns; }
    std::uint64_t period_ns() const { return period_ns_; }

    Role role() const { return role_; }
    const ModeInfo* mode() const { return mode_; }
    bool active() const { return channel_ && role_ != Role::Off; }
    // The slave runs on the master's set-points (P0165 = TWINSYNC) in a mode that follows.
    bool follows() const;
    bool controlled_by_twinsync() const;  // P0159 = TWINSYNC on a slave

    void receive(std::uint64_t t_ns, const LocalState& local);
    void transmit(std::uint64_t t_ns, const LocalState& local);

    // Valid data from the partner has arrived since the link became active (values may be frozen).
    bool has_data() const { return has_data_; }
    // A valid telegram arrived in this cycle's receive.
    bool received_fresh() const { return fresh_; }
    // P0149 MPRO_DRVCOM_Init: the link initialises again (4.1.2).
    void initialise();
    // P0301 is what the slave table of the operation mode requires (IP-Mode), or the mode requires nothing.
    bool setpoint_mode_fits() const;
    bool link_ok() const { return status_.link_ok; }
    // P2611 on a slave: from the telegram's control word (standard layout) or, in the extended layout, from
    // wherever the user mapped P2611.
    std::uint16_t received_control_word() const;
    const TwinStatusWord& partner() const { return partner_; }
    bool partner_enabled() const;  // the partner reports DriveCom state 5 (Control)
    // The monitoring's finding this cycle (the drive raises it as a fault in state Control).
    std::optional<ErrorId> pending_error() const { return pending_; }
    // The error the drive has raised: sent in the status word and shown in P2650.
    void set_error(std::optional<ErrorId> e) { raised_ = e; }

    const LinkStatus& status() const { return status_; }
    // The active receive mapping writes this parameter.
    bool receives(std::uint16_t parameter) const;
    // Re-reads the configuration (called after SDO writes; cheap when nothing changed).
    void reconfigure();
    // Why the last write was refused ("" if it was not).
    const std::string& message() const { return message_; }

  private:
    struct Mapped {
        coe::Entry* entry = nullptr;
        std::size_t bytes = 0;
    };
    struct Config;
    protocol::SdoAbort validate_write(coe::Entry& e, ConstBytes value);
    protocol::SdoAbort check_configuration();
    bool resolve(const MappingWords& words, bool extended, std::vector<Mapped>& out, std::size_t& bytes,
                 std::string& why) const;
    void set_message(std::string m);
    void apply_fault_injection();
    void monitor(const LocalState& local, bool valid);

    std::shared_ptr<Channel> channel_;
    int end_ = 0;
    Role role_ = Role::Off;
    coe::ObjectDictionary& od_;
    std::uint64_t period_ns_;
    std::unique_ptr<Config> c_;

    const ModeInfo* mode_ = nullptr;
    Layout layout_ = Layout::Standard;
    std::size_t pdo_size_ = 0;
    std::vector<Mapped> send_, receive_;
    bool configured_ = false;

    SyncController sync_;
    bool has_data_ = false;
    bool fresh_ = false;
    std::uint16_t rx_drivecom_ = 0;
    TwinStatusWord partner_;
    double fault_time_ns_ = 0;
    double state_mismatch_ns_ = 0;
    std::optional<ErrorId> pending_;
    std::optional<ErrorId> raised_;
    LinkStatus status_;
    std::string message_;
};

}  // namespace vecat::twinsync
