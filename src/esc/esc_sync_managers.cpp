// The ESC's SyncManagers (part of class Esc, see esc.cpp): their state from the register blocks
// 0x0800 + 8 n, the ECAT accesses of their areas (mailbox, three buffers, one byte, locked when the PDI
// deactivated them) and the PDI side; which SyncManager guards an address is inline in esc.hpp (every
// access of the process RAM asks it). ESC datasheet section I chapter 8; the rules are listed in README.md.
#include <algorithm>
#include <cstring>

#include "esc/esc.hpp"

namespace vecat::esc {

using protocol::addr;
using protocol::kMaxSms;
using protocol::kRegisterSpaceSize;
using protocol::kSmSize;
using protocol::Reg;
using protocol::sm_addr;
using protocol::SmConfig;
namespace al_event = protocol::al_event;
namespace sm = protocol::sm;

bool Esc::sm_ecat_read(unsigned i, std::size_t off, std::uint8_t* dst, std::size_t n, bool or_into) {
    SmState& s = sm_[i];
    if (s.single) {  // no buffer mechanism: the memory, in either direction
        copy_out(dst, &mem_[s.start + off], n, or_into);
        if (!s.ecat_writes) set_al_event(al_event::sm(i));
        return true;
    }
    if (s.ecat_writes) return false;  // the master may not read a buffer it writes
    const std::uint8_t* src;
    if (s.mailbox) {
        if (!s.mbx_full) return false;  // empty mailbox: not counted
        src = &mem_[s.start + off];
        if (off == 0 && s.irq_write) {
            s.irq_write = false;
            update_sm_status(i);
        }
    } else {
        if (!s.ecat_reading) {
            if (s.buf_next != SmState::kNone) {
                s.buf_ecat = s.buf_next;
                s.buf_next = SmState::kNone;
            }
            s.ecat_reading = true;
        }
        src = &mem_[s.start + static_cast<std::size_t>(s.buf_ecat) * s.length + off];
    }
    copy_out(dst, src, n, or_into);
    if (off + n == s.length) {  // last byte read: buffer released
        if (s.mailbox) {
            s.mbx_full = false;
            s.irq_read = true;
            firmware_work_ = true;  // the firmware may post its next message
        } else
            s.ecat_reading = false;
        set_al_event(al_event::sm(i));
        update_sm_status(i);
    }
    return true;
}

bool Esc::sm_ecat_write(unsigned i, std::size_t off, const std::uint8_t* src, std::size_t n) {
    SmState& s = sm_[i];
    if (s.single) {  // no buffer mechanism; the watchdog trigger and the event still work (section I 8.5)
        std::memcpy(&mem_[s.start + off], src, n);
        if (!s.ecat_writes) return true;
        if (s.control & sm::CtrlWatchdog) {
            wd_armed_ = true;
            wd_last_trigger_ns_ = last_host_ns_;
            mem_[addr(Reg::WatchdogStatusProcessData)] |= 0x01;
        }
        s.ever_written = true;
        ++s.complete_writes;
        set_al_event(al_event::sm(i));
        return true;
    }
    if (!s.ecat_writes) return false;
    if (s.mailbox) {
        if (s.mbx_full) return false;  // full mailbox: refused, not counted (masters retry)
        std::memcpy(&mem_[s.start + off], src, n);
        if (off == 0) s.irq_read = false;
        if (off + n == s.length) {
            s.mbx_full = true;
            s.irq_write = true;
            s.ever_written = true;
            ++s.complete_writes;
            set_al_event(al_event::sm(i));
            update_sm_status(i);
        }
        return true;
    }
    std::memcpy(&mem_[s.start + static_cast<std::size_t>(s.buf_ecat) * s.length + off], src, n);
    if (s.control & sm::CtrlWatchdog) {
        wd_armed_ = true;
        wd_last_trigger_ns_ = last_host_ns_;
        mem_[addr(Reg::WatchdogStatusProcessData)] |= 0x01;
    }
    if (off + n == s.length) {  // last byte written: the buffer becomes the newest complete one
        s.buf_next = s.buf_ecat;
        s.buf_ecat = static_cast<std::uint8_t>(3 - s.buf_next - s.buf_pdi);
        s.ever_written = true;
        ++s.complete_writes;
        set_al_event(al_event::sm(i));
        update_sm_status(i);
    }
    return true;
}

protocol::SmConfig Esc::sm_block(unsigned i) const {
    return SmConfig::unpack(std::span<const std::uint8_t, kSmSize>(&mem_[sm_addr(i)], kSmSize));
}

Esc::SmConfigView Esc::sm_config(unsigned i) const {
    const SmConfig c = sm_block(i);
    return {c.physical_start, c.length, c.control, c.enabled(), c.pdi_deactivated(), sm_[i].valid};
}

void Esc::update_sm(unsigned i) {
    if (i >= cfg_.sm_count) return;
    const SmConfig c = sm_block(i);
    SmState& s = sm_[i];
    const std::uint16_t start = c.physical_start;
    const std::uint16_t length = c.length;
    const std::uint8_t control = c.control;
    const bool mode_ok = (control & sm::CtrlModeMask) == sm::CtrlModeBuffered || c.mailbox();
    const bool dir_ok =
        (control & sm::CtrlDirMask) == sm::CtrlDirRead || (control & sm::CtrlDirMask) == sm::CtrlDirWrite;
    const bool mailbox = c.mailbox();
    const bool single = !mailbox && length == 1;
    const std::size_t span = mailbox || single ? length : 3u * length;
    const bool valid =
        mode_ok && dir_ok && length > 0 && sm_area_exists(start, static_cast<std::uint32_t>(span));
    const bool active = c.enabled() && !c.pdi_deactivated() && valid;
    // Deactivated by the PDI while the master has it enabled: the whole area stays locked (ESC datasheet
    // section I 8.7; register 0x0807 bit 0 "SyncManager locks access to memory area"). Only a SyncManager
    // the master disabled (0x0806 bit 0 = 0) leaves plain memory behind.
    const bool locked = c.enabled() && c.pdi_deactivated() && length > 0 && sm_area_exists(start, length);
    const bool changed = active != s.active || locked != s.locked || start != s.start || length != s.length ||
                         control != s.control;
    const bool repeat = c.repeat_request();
    static_assert(kMaxSms <= 32);
    const bool was_repeat = (repeat_bits_ >> i) & 1u;
    s.valid = valid;
    if (changed) {
        s.active = active;
        s.locked = locked;
        s.start = start;
        s.length = length;
        s.control = control;
        s.mailbox = mailbox;
        s.single = single;
        s.ecat_writes = c.ecat_writes();
        s.mbx_full = false;
        s.irq_write = s.irq_read = false;
        s.pdi_opened = false;
        s.ecat_reading = false;
        s.ever_written = false;
        s.buf_next = SmState::kNone;
        if (s.ecat_writes) {
            s.buf_ecat = 0;
            s.buf_pdi = 1;
        } else {
            s.buf_pdi = 0;
            s.buf_ecat = 1;
        }
        sm_activation_event_ = true;
        set_al_event(al_event::SmActivation);
        update_prefetch_sms();
    }
    if (repeat != was_repeat) {
        repeat_bits_ = repeat ? (repeat_bits_ | (1u << i)) : (repeat_bits_ & ~(1u << i));
        sm_activation_event_ = true;
        set_al_event(al_event::SmActivation);
    }
    if (active || locked)
        sm_guard_mask_ |= 1u << i;
    else
        sm_guard_mask_ &= ~(1u << i);
    update_sm_status(i);
}

void Esc::update_prefetch_sms() {
    prefetch_sm_count_ = 0;
    for (unsigned i = 0; i < cfg_.sm_count && prefetch_sm_count_ < kPrefetchSms; ++i) {
        const SmState& s = sm_[i];
        if (!s.active || s.mailbox) continue;
        prefetch_sms_[prefetch_sm_count_++] = {
            static_cast<std::uint8_t>(i), s.start,
            static_cast<std::uint16_t>(s.single ? s.length : 3u * s.length)};
    }
}

bool Esc::has_digital_io() const {
    return protocol::pdi_is_digital_io(mem_[addr(Reg::PdiControl)]);
}

bool Esc::sm_area_exists(std::uint32_t start, std::uint32_t span) const {
    if (start >= kRegisterSpaceSize) return start + span <= mem_.size();
    const std::uint32_t dout = addr(Reg::DigitalOutputData);
    return has_digital_io() && start >= dout && start + span <= dout + protocol::kDigitalOutputSize;
}

void Esc::update_sm_status(unsigned i) {
    const SmState& s = sm_[i];
    std::uint8_t st = 0;
    if (!s.active) {
        st = 0;
    } else if (s.mailbox) {
        if (s.mbx_full) st |= sm::StatusMailboxFull;
        if (s.irq_write) st |= sm::StatusIrqWrite;
        if (s.irq_read) st |= sm::StatusIrqRead;
        if (s.pdi_opened) st |= sm::StatusWriteBufferInUse;
    } else {
        const std::uint8_t last =
            s.buf_next != SmState::kNone ? s.buf_next : (s.ecat_writes ? s.buf_pdi : s.buf_ecat);
        st = static_cast<std::uint8_t>((last & 0x3) << sm::StatusBufferShift);
        if (s.buf_next != SmState::kNone) st |= sm::StatusIrqWrite;
        if (s.ecat_reading) st |= sm::StatusReadBufferInUse;
    }
    mem_[sm_addr(i) + sm::Status] = st;
}

bool Esc::pdi_take_sm_activation_event() {
    const bool e = sm_activation_event_;
    sm_activation_event_ = false;
    clear_al_event(al_event::SmActivation);
    return e;
}

void Esc::pdi_deactivate_sm(unsigned i, bool deactivate) {
    if (i >= cfg_.sm_count) return;
    std::uint8_t& pc = mem_[sm_addr(i) + sm::PdiControl];
    pc = static_cast<std::uint8_t>(deactivate ? (pc | sm::PdiDeactivate) : (pc & ~sm::PdiDeactivate));
    update_sm(i);
}

bool Esc::sm_repeat_request(unsigned i) const {
    return (mem_[sm_addr(i) + sm::Activate] & sm::ActRepeatRequest) != 0;
}

void Esc::pdi_set_repeat_ack(unsigned i, bool ack) {
    std::uint8_t& pc = mem_[sm_addr(i) + sm::PdiControl];
    pc = static_cast<std::uint8_t>(ack ? (pc | sm::PdiRepeatAck) : (pc & ~sm::PdiRepeatAck));
}

bool Esc::pdi_mailbox_take(unsigned i, Bytes out) {
    SmState& s = sm_[i];
    if (i >= cfg_.sm_count || !s.active || !s.mailbox || !s.ecat_writes || !s.mbx_full) return false;
    std::memcpy(out.data(), &mem_[s.start], std::min<std::size_t>(out.size(), s.length));
    s.mbx_full = false;
    s.irq_write = false;
    s.irq_read = true;
    clear_al_event(al_event::sm(i));
    update_sm_status(i);
    return true;
}

bool Esc::pdi_mailbox_put(unsigned i, ConstBytes data) {
    SmState& s = sm_[i];
    if (i >= cfg_.sm_count || !s.active || !s.mailbox || s.ecat_writes || s.mbx_full) return false;
    const std::size_t n = std::min<std::size_t>(data.size(), s.length);
    std::memcpy(&mem_[s.start], data.data(), n);
    std::memset(&mem_[s.start + n], 0, s.length - n);
    s.mbx_full = true;
    s.irq_write = true;
    s.irq_read = false;
    s.pdi_opened = false;
    update_sm_status(i);
    return true;
}

void Esc::pdi_mailbox_open(unsigned i) {
    if (i >= cfg_.sm_count) return;
    SmState& s = sm_[i];
    if (!s.active || !s.mailbox || s.ecat_writes || s.mbx_full || !s.irq_read || s.pdi_opened) return;
    s.pdi_opened = true;
    s.irq_read = false;  // cleared by the first byte written (section II 0x0805 bit 1)
    update_sm_status(i);
}

bool Esc::pdi_buffer_read(unsigned i, Bytes out) {
    SmState& s = sm_[i];
    if (i >= cfg_.sm_count || !s.active || !s.ecat_writes) return false;
    if (s.mailbox) {  // 1-buffer mode: a complete buffer is taken, the last one stays readable
        if (s.mbx_full) {
            s.mbx_full = false;
            s.irq_write = false;
            s.irq_read = true;
            clear_al_event(al_event::sm(i));
            update_sm_status(i);
        }
        if (!s.ever_written) return false;
        std::memcpy(out.data(), &mem_[s.start], std::min<std::size_t>(out.size(), s.length));
        return true;
    }
    if (s.single) {
        clear_al_event(al_event::sm(i));
        if (!s.ever_written || out.empty()) return false;
        out[0] = mem_[s.start];
        return true;
    }
    if (s.buf_next != SmState::kNone) {
        s.buf_pdi = s.buf_next;
        s.buf_next = SmState::kNone;
        clear_al_event(al_event::sm(i));
        update_sm_status(i);
    }
    if (!s.ever_written) return false;
    std::memcpy(out.data(), &mem_[s.start + static_cast<std::size_t>(s.buf_pdi) * s.length],
                std::min<std::size_t>(out.size(), s.length));
    return true;
}

bool Esc::pdi_buffer_write(unsigned i, ConstBytes in) {
    SmState& s = sm_[i];
    if (i >= cfg_.sm_count || !s.active || s.ecat_writes) return false;
    if (s.mailbox) return pdi_mailbox_put(i, in);  // 1-buffer mode: only once the master read the last
    if (s.single) {
        if (!in.empty()) mem_[s.start] = in[0];
        return true;
    }
    std::uint8_t* dst = &mem_[s.start + static_cast<std::size_t>(s.buf_pdi) * s.length];
    const std::size_t n = std::min<std::size_t>(in.size(), s.length);
    std::memcpy(dst, in.data(), n);
    if (n < s.length) std::memset(dst + n, 0, s.length - n);
    s.buf_next = s.buf_pdi;
    s.buf_pdi = static_cast<std::uint8_t>(3 - s.buf_next - s.buf_ecat);
    update_sm_status(i);
    return true;
}

void Esc::pdi_write_memory(std::uint16_t a, ConstBytes in) {
    if (a < kRegisterSpaceSize || a >= mem_.size()) return;  // the process RAM only
    std::memcpy(&mem_[a], in.data(), std::min<std::size_t>(in.size(), mem_.size() - a));
}

void Esc::pdi_read_memory(std::uint16_t a, Bytes out) const {
    if (a >= mem_.size()) return;
    std::memcpy(out.data(), &mem_[a], std::min<std::size_t>(out.size(), mem_.size() - a));
}

}  // namespace vecat::esc
