// What differs between the drives the CoE adapter (drive.hpp) runs, besides the device description: the
// strategies of the drive core (drive_io.hpp DriveStrategy: homing convention, 0x60C2 format, touch probe
// trigger, the home switch dog) and the device's own manufacturer objects. The vecat drive's manufacturer
// objects are bound by the adapter itself; a variant with other ones (the HIWIN D2's 0x2000-0x2101, HIWIN
// guide 3.6/3.7) brings them here, bound once to the dictionary like the adapter's.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "cia402/drive_io.hpp"
#include "coe/object_dictionary.hpp"
#include "device/device_description.hpp"

namespace vecat::cia402 {

// The core's strategies of a variant, and the simulated machine of a variant whose dictionary has no
// objects for it (the vecat drive's has, 0x2100: it leaves p alone).
DriveStrategy drive_strategy(device::DriveVariant v);
void simulated_machine(device::DriveVariant v, DriveParameters& p);

class VariantObjects {
  public:
    // The variant of a device (device::DeviceDescription::drive_variant) on its dictionary.
    static std::unique_ptr<VariantObjects> make(device::DriveVariant v, coe::ObjectDictionary& od);
    virtual ~VariantObjects() = default;

    // Whether the vecat drive's manufacturer objects (device/drive_objects.hpp) are this device's.
    virtual bool vecat_objects() const { return true; }
    // The entries read with the parameters or with the command (the adapter counts their writes).
    virtual std::vector<coe::Entry*> parameter_entries() { return {}; }
    virtual std::vector<coe::Entry*> command_entries() { return {}; }
    // SDO rules and actions of the device's objects. zero_position: sets the actual position to 0.
    virtual void install(std::function<void()> zero_position) { (void)zero_position; }
    virtual void read_parameters(DriveParameters&) const {}
    virtual void read_command(DriveCommand&) const {}
    virtual void write_feedback(const DriveIo&) {}
    // The slave's synchronisation: DC SYNC0 with its cycle time (0: free run or SM-synchronous). True when
    // it wrote a parameter.
    virtual bool synchronised(std::uint32_t sync0_cycle_ns) {
        (void)sync0_cycle_ns;
        return false;
    }
};

}  // namespace vecat::cia402
