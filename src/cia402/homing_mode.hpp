// Homing mode (HM, mode 6; CiA 402 / IEC 61800-7-201 6.6): controlword bit 4 rising starts the homing method
// 0x6098 (homing.hpp: the methods themselves), with the speeds 0x6099 and the acceleration 0x609A; bit 4
// falling or halt (bit 8) interrupts it. Once the home is found the coordinate system moves so that the
// home position reads as the home offset 0x607C. Statusword bits 10/12/13: homing.hpp's statusword_bits()
// (13/12/10 = 1/0/1 when the method could not start).
#pragma once

#include <cstdint>
#include <optional>

#include "cia402/homing.hpp"
#include "cia402/operation_mode.hpp"

namespace vecat::cia402 {

// HIWIN guide 9.4: statusword bit 15, "accuracy compensation initiated".
inline constexpr std::uint16_t kAccuracyCompensation = 1u << 15;

// The method of homing.hpp a 0x6098 value selects under a convention; nullopt: none (HIWIN's 0, "No homing
// mode", and values the convention does not define).
//   HIWIN 1, 2, 33, 34: as CiA 402. HIWIN 3-6 search a home switch the axis can pass through (a dog):
//   3 positive, back out of its lower edge (CiA 402's window method 7); 4 positive, on through its upper edge
//   (10); 5 negative, back out of its upper edge (11); 6 negative, on through its lower edge (14). Each then
//   takes the first index pulse.
std::optional<int> homing_method_of(HomingConvention c, int value);

class HomingMode final : public OperationMode {
  public:
    HomingMode() : OperationMode(true) {}
    void reset() override;
    void step(Axis& a, double dt) override;
    ModeStatus status(const Axis& a, const StatusInputs& in) override;
    // Statusword bits 10, 12, 13 of the last period (also shown outside OPERATION ENABLED).
    std::uint16_t bits() const { return bits_; }
    // Homing attained (bit 12 without the error bit 13).
    bool attained() const { return (bits_ & sw::Bit12) && !(bits_ & sw::Bit13); }
    // HIWIN 9.4: the accuracy compensation ran after this homing (0x2010 bit 0): the position reads 0.
    bool compensated() const { return compensated_; }

  private:
    Homing homing_;
    std::uint16_t bits_ = 0;  // statusword bits 10, 12, 13 from the homing method
    bool active_ = false;
    bool error_ = false;  // the method could not start (unsupported method, bad speeds)
    bool compensated_ = false;
    double velocity_ = 0;  // velocity the profile runs at for the homing method
};

}  // namespace vecat::cia402
