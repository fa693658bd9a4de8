// The application of a CoE slave: its object dictionary, PDO mapping and SDO server, and the process data
// exchange through the mapped objects. Device behaviour (the CiA 402 drive) derives from it and runs in
// cycle(), between reading the outputs and writing the inputs.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "coe/parameter_store.hpp"
#include "coe/pdo_mapping.hpp"
#include "coe/sdo_server.hpp"
#include "coe/sync_parameters.hpp"
#include "esc/segment.hpp"
#include "esc/slave.hpp"
#include "protocol/coe.hpp"

namespace vecat::coe {

// Error register 0x1001 bits (CiA 301 7.5.2.2), protocol/coe.hpp.
namespace error_register = protocol::error_register;

// Emergency error codes used for EtherCAT state machine errors (ETG.1000.6 Table 53 / CiA 301).
namespace emcy {
inline constexpr std::uint16_t ErrorReset = 0x0000;
inline constexpr std::uint16_t Communication = 0x8100;
inline constexpr std::uint16_t LifeGuard = 0x8130;  // used for the SyncManager watchdog
inline constexpr std::uint16_t PdoLength = 0x8210;
inline constexpr std::uint16_t PreOpToSafeOp = 0xA000;
inline constexpr std::uint16_t SafeOpToOp = 0xA001;
inline constexpr std::uint16_t DataSet = 0x6300;  // CiA 301: stored parameters unusable
}  // namespace emcy

class CoeApplication : public esc::Application {
  public:
    // objects: dictionary_objects(d) built once for many applications (esc::DeviceModel::dictionary); empty:
    // built here.
    explicit CoeApplication(const device::DeviceDescription& d,
                            std::shared_ptr<const std::vector<device::ObjectDescription>> objects = {});
    ~CoeApplication() override;

    ObjectDictionary& dictionary() { return od_; }
    ProcessDataMap& process_data() { return *map_; }
    SdoServer& sdo_server() { return *sdo_; }
    AlState state() const { return state_; }

    // Sets 0x1001 bits and 0x603F (if present), and queues an emergency with the AL status code or
    // manufacturer data.
    void raise_fault(std::uint16_t error_code, std::uint8_t register_bits,
                     std::array<std::uint8_t, 5> data = {});
    // Clears 0x1001/0x603F and sends the "error reset" emergency.
    void clear_faults();

    // Fault injection (`vecat fault` encoder, over_current, following_error): whether the application
    // simulates device faults, and the 0x603F code of the one to simulate (0: none). By default through the
    // vecat drive's object 0x2101 (UNSIGNED16), when the dictionary has it; a device whose 0x2101 is its
    // own (the HIWIN D2's error events) overrides both.
    virtual bool simulates_faults();
    virtual void simulate_fault(std::uint16_t code);

    // esc::Application
    unsigned output_bytes() const override { return map_->output_bytes(); }
    unsigned input_bytes() const override { return map_->input_bytes(); }
    protocol::AlStatusCode check_transition(AlState from, AlState to) override;
    void on_state_change(AlState from, AlState to) override;
    void on_al_error(protocol::AlStatusCode code) override;
    void exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply_outputs, Bytes inputs) override;
    void outputs_safe_state() override;
    esc::MailboxProtocol* mailbox_protocol(protocol::MailboxType t) override;
    void tick(std::uint64_t now_ns) override;
    void sync_event(unsigned signal, std::uint64_t now_ns) override;
    bool refresh_inputs(Bytes inputs) override;
    void attach(esc::Slave& slave) override;
    esc::OpReadiness op_readiness(std::uint64_t now_ns, std::uint64_t since_ns) override;
    // A firmware update (the bootloader, src/foe): 0x1018:03 reports the new revision.
    void on_revision_change(std::uint32_t revision) override;
    std::uint64_t next_event_ns() const override;

    // Parameter persistence (0x1010/0x1011) in the file at path: applies the stored set now. A corrupted
    // or foreign file leaves the defaults and queues an emergency 0x6300 (data set) with "PRM" and the
    // LoadStatus in its manufacturer bytes; the caller reports the returned detail on stderr.
    RestoreReport attach_parameter_store(std::string path);
    ParameterStore* parameter_store() { return store_.get(); }

    std::uint64_t exchanges() const { return exchanges_; }
    // Synchronisation chosen at PREOP -> SAFEOP (0x1C32:01) and the application cycle: the SYNC0 (SYNC1)
    // cycle time in DC mode, 0x1C32:02 otherwise, 0 if unknown.
    SyncMode sync_mode() const { return sync_->mode(); }
    std::uint64_t cycle_time_ns() const { return sync_->cycle_time_ns(); }
    SyncParameters& sync_parameters() { return *sync_; }

  protected:
    // A counter of the device's that each AL state change and each transition checked increments: the
    // synchronisation (sync_mode, cycle_time_ns) changes only then (SyncParameters), so that the device can
    // tell that it did not change without looking (cia402::Drive counts it with its parameters' writes).
    void watch_synchronisation(std::uint32_t* counter) { sync_watch_ = counter; }
    // In DC mode (SYNC0 or SYNC1 synchronous), as of the last transition.
    bool dc_mode() const { return dc_; }
    // The device's own step, after new outputs were stored in the dictionary and before the inputs are
    // read from it. outputs_applied is false below OP or without new outputs. In free run and SM-synchronous
    // mode it runs on every process data exchange; in DC mode on every SYNC0 (SYNC1) event, after the outputs
    // received since the previous event were stored (outputs_applied: in OP with valid outputs).
    virtual void cycle(std::uint64_t /*now_ns*/, bool /*outputs_applied*/) {}
    // The device's own time up to now_ns with the outputs it has, before new ones are stored: a device
    // that runs in periods of its own (a drive's servo periods) runs those that ended by then. New outputs
    // then take effect after the exchange or the SYNC event that brought them, whenever the firmware ran
    // last (ticks between frames or not: the results are the same).
    virtual void advance_to(std::uint64_t /*now_ns*/) {}

  private:
    ObjectDictionary od_;
    std::unique_ptr<ProcessDataMap> map_;
    std::unique_ptr<SdoServer> sdo_;
    std::unique_ptr<SyncParameters> sync_;
    std::uint32_t* sync_watch_ = nullptr;  // watch_synchronisation
    std::unique_ptr<ParameterStore> store_;
    device::Identity identity_;
    bool outputs_received_ = false;  // in OP, outputs were applied (DC mode cycles use the last ones)
    // sync_->dc_mode(), kept here: it changes only at a transition (SyncParameters), and a run of a device
    // outside DC mode then need not look at the SyncParameters at all.
    bool dc_ = false;
    // DC mode: the outputs of the last frame, stored into the dictionary at the next sync event.
    std::vector<std::uint8_t> pending_outputs_;
    bool outputs_pending_ = false;
    // DC mode: the inputs were latched at a SYNC event since the state changed; exchanges leave them as
    // they were latched until the next event.
    bool inputs_latched_ = false;
    AlState state_ = AlState::Init;
    AlState requested_ = AlState::Init;  // target of the transition being checked (emergency code)
    Entry* error_register_ = nullptr;
    Entry* error_code_ = nullptr;
    std::uint64_t exchanges_ = 0;
};

// A segment of n slaves of the device, each served by a CoeApplication.
std::unique_ptr<esc::Segment> make_coe_segment(const device::DeviceDescription& d, std::size_t n,
                                               const esc::EscConfig& cfg = {});
// The same from a model built once (esc::DeviceModel::of).
std::unique_ptr<esc::Segment> make_coe_segment(const esc::DeviceModel& m, std::size_t n,
                                               const esc::EscConfig& cfg = {});

}  // namespace vecat::coe
