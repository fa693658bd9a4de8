#include "foe/foe_server.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace vecat::foe {

using protocol::AlState;
using protocol::FoeError;
using protocol::FoeOpCode;
using protocol::MailboxType;

namespace {

// What a message of the master does in each state of the server (ETG.1000.6 5.8: read and write requests,
// data, acknowledge, error, busy).
enum class Action : std::uint8_t {
    StartRead,   // a new read request (ends a transfer in progress, as a master's retry would)
    StartWrite,  // a new write request (likewise)
    Data,        // the next packet of a write
    Ack,         // the acknowledge of the last packet of a read
    Cancel,      // the master's error request: the transfer ends, nothing is answered
    Illegal,     // the opcode makes no sense now: FoE error 0x8004 "illegal", the transfer ends
};

using A = Action;
// Rows: FoeState (Idle, Reading, Writing); columns: FoeOpCode 1..6 (Read, Write, Data, Ack, Error, Busy).
// A busy message comes from a slave, never from a master: illegal in every state.
constexpr Action kTable[3][6] = {
    /* Idle    */ {A::StartRead, A::StartWrite, A::Illegal, A::Illegal, A::Cancel, A::Illegal},
    /* Reading */ {A::StartRead, A::StartWrite, A::Illegal, A::Ack, A::Cancel, A::Illegal},
    /* Writing */ {A::StartRead, A::StartWrite, A::Data, A::Illegal, A::Cancel, A::Illegal},
};

// What the busy message of a firmware write tells: nothing done yet of 100 (per cent).
constexpr std::uint16_t kBusyEntire = 100;
constexpr std::string_view kBusyText = "erasing flash";

std::string hex32(std::uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%08X", v);
    return b;
}

}  // namespace

FoeServer::FoeServer(esc::Slave& slave, FoeOptions options, std::string dir)
    : slave_(slave), options_(std::move(options)), store_(std::move(dir), options_.max_file_size) {
    const auto i = slave_.description().sm_index_of_type(device::SmType::MailboxOut);
    if (i && *i < protocol::kMaxSms) sm_out_ = static_cast<int>(*i);
}

std::size_t FoeServer::receive_capacity() const {
    if (sm_out_ < 0) return 0;
    return protocol::foe_data_capacity(slave_.esc().sm_config(static_cast<unsigned>(sm_out_)).length);
}

void FoeServer::handle(const protocol::MailboxHeader&, ConstBytes payload, esc::MailboxReplySink& out) {
    const auto m = protocol::parse_foe(payload);
    if (!m) {
        idle();
        if (payload.size() < protocol::kFoeHeaderSize) {
            // Not even an opcode and its 4-byte field: the mailbox layer's answer (ETG.1000.4 Table 30).
            ++counters_.errors_sent;
            const std::size_t n =
                protocol::make_mailbox_error(out.reply_buffer(), protocol::MailboxError::SizeTooShort);
            out.commit(MailboxType::Error, n);
        } else {
            error(FoeError::Illegal, out, "unknown FoE opcode");
        }
        return;
    }
    const auto col = static_cast<unsigned>(m->op) - static_cast<unsigned>(FoeOpCode::Read);
    switch (kTable[static_cast<unsigned>(state_)][col]) {
        case Action::StartRead:
            start_read(m->value, trim_file_name(m->text()), out);
            break;
        case Action::StartWrite:
            start_write(m->value, trim_file_name(m->text()), out);
            break;
        case Action::Data:
            take_data(m->value, m->tail, out);
            break;
        case Action::Ack:
            take_ack(m->value, out);
            break;
        case Action::Cancel:
            idle();  // ETG.1000.6 5.8.5: the error request ends the transfer; it is not answered
            break;
        case Action::Illegal:
            error(FoeError::Illegal, out, "unexpected opcode");
            break;
    }
}

std::optional<FoeError> FoeServer::check_request(std::uint32_t password, std::string_view name,
                                                 bool firmware) const {
    if (!valid_file_name(name)) return FoeError::Illegal;
    const bool boot = slave_.state() == AlState::Boot;
    if (firmware && !boot) return FoeError::BootstrapOnly;   // the firmware file: BOOT only
    if (!firmware && boot) return FoeError::NotInBootstrap;  // in BOOT the bootloader knows no other file
    if (password != options_.password) return FoeError::NoRights;
    return std::nullopt;
}

void FoeServer::start_read(std::uint32_t password, std::string_view name, esc::MailboxReplySink& out) {
    idle();
    const bool firmware = is_firmware_name(name);
    if (const auto e = check_request(password, name, firmware)) return error(*e, out);
    if (firmware) return error(FoeError::AccessDenied, out, "the firmware cannot be read back");
    std::string why;
    switch (store_.read(name, buf_, &why)) {
        case StoreStatus::Ok:
            break;
        case StoreStatus::NotFound:
            return error(FoeError::NotFound, out);
        case StoreStatus::AccessDenied:
            return error(FoeError::AccessDenied, out);
        default:
            return error(FoeError::NotDefined, out, why);
    }
    ++counters_.reads;
    state_ = FoeState::Reading;
    name_ = name;
    send_data(out);
}

void FoeServer::send_data(esc::MailboxReplySink& out) {
    const Bytes b = out.reply_buffer();
    const std::size_t cap = b.size() > protocol::kFoeHeaderSize ? b.size() - protocol::kFoeHeaderSize : 0;
    if (cap == 0) return error(FoeError::NotDefined, out, "the reply mailbox is too small");
    offset_ += last_len_;
    last_len_ = std::min(cap, buf_.size() - offset_);
    last_sent_ = last_len_ < cap;  // a full packet is followed by another, maybe empty (ETG.1000.6 5.8.4)
    ++packet_;
    const std::size_t n = protocol::write_foe_data(b, packet_, ConstBytes(buf_.data() + offset_, last_len_));
    out.commit(MailboxType::FoE, n);
}

void FoeServer::take_ack(std::uint32_t packet, esc::MailboxReplySink& out) {
    if (packet != packet_)
        return error(FoeError::PacketNumberWrong, out,
                     "acknowledge of packet " + std::to_string(packet) + ", sent " + std::to_string(packet_));
    if (last_sent_) {
        ++counters_.files_read;
        idle();  // the acknowledge of the last packet ends the read; it is not answered
        return;
    }
    send_data(out);
}

void FoeServer::start_write(std::uint32_t password, std::string_view name, esc::MailboxReplySink& out) {
    idle();
    const bool firmware = is_firmware_name(name);
    if (const auto e = check_request(password, name, firmware)) return error(*e, out);
    ++counters_.writes;
    state_ = FoeState::Writing;
    name_ = name;
    firmware_ = firmware;
    busy_pending_ = firmware && options_.busy_on_erase;
    packet_ = 0;
    const std::size_t n = protocol::write_foe_ack(out.reply_buffer(), 0);
    out.commit(MailboxType::FoE, n);
}

void FoeServer::take_data(std::uint32_t packet, ConstBytes data, esc::MailboxReplySink& out) {
    if (packet != packet_ + 1)
        return error(FoeError::PacketNumberWrong, out,
                     "packet " + std::to_string(packet) + ", expected " + std::to_string(packet_ + 1));
    if (busy_pending_) {
        // The packet is not taken: the master sends it again after the busy answer (ETG.1000.6 5.8.4).
        busy_pending_ = false;
        ++counters_.busy_sent;
        const std::size_t n = protocol::write_foe_busy(out.reply_buffer(), 0, kBusyEntire, kBusyText);
        out.commit(MailboxType::FoE, n);
        return;
    }
    if (data.size() > options_.max_file_size - buf_.size())
        return error(FoeError::DiskFull, out,
                     "larger than the size limit of " + std::to_string(options_.max_file_size) + " bytes");
    buf_.insert(buf_.end(), data.begin(), data.end());
    packet_ = packet;
    if (data.size() >= receive_capacity() && receive_capacity() > 0) {
        const std::size_t n = protocol::write_foe_ack(out.reply_buffer(), packet_);
        out.commit(MailboxType::FoE, n);
        return;
    }
    finish_write(out);
}

void FoeServer::finish_write(esc::MailboxReplySink& out) {
    std::optional<FirmwareHeader> fw;
    if (firmware_) {
        std::string why;
        fw = parse_firmware(buf_, &why);
        if (!fw) return error(FoeError::ProgramError, out, why);
        const std::uint32_t product = slave_.description().identity.product_code;
        if (fw->product && *fw->product != product)
            return error(
                FoeError::ProgramError, out,
                "firmware for product " + hex32(*fw->product) + ", this device is " + hex32(product));
    }
    std::string why;
    switch (store_.write(name_, buf_, &why)) {
        case StoreStatus::Ok:
            break;
        case StoreStatus::TooLarge:
        case StoreStatus::Full:
            return error(FoeError::DiskFull, out);
        case StoreStatus::AccessDenied:
            return error(FoeError::AccessDenied, out);
        default:
            return error(FoeError::NotDefined, out, why);
    }
    if (fw) pending_revision_ = fw->revision;
    ++counters_.files_written;
    const std::uint32_t last = packet_;
    idle();
    const std::size_t n = protocol::write_foe_ack(out.reply_buffer(), last);
    out.commit(MailboxType::FoE, n);
}

void FoeServer::error(FoeError e, esc::MailboxReplySink& out, std::string_view text) {
    idle();
    ++counters_.errors_sent;
    const std::string t = text.empty() ? std::string(protocol::describe(e))
                                       : std::string(protocol::describe(e)) + ": " + std::string(text);
    const std::size_t n = protocol::write_foe_error(out.reply_buffer(), e, t);
    out.commit(MailboxType::FoE, n);
}

void FoeServer::idle() {
    state_ = FoeState::Idle;
    name_.clear();
    firmware_ = false;
    busy_pending_ = false;
    packet_ = 0;
    offset_ = 0;
    last_len_ = 0;
    last_sent_ = false;
    std::vector<std::uint8_t>().swap(buf_);  // a file's memory is given back between transfers
}

void FoeServer::reset() {
    idle();
}

void FoeServer::on_state_change(AlState from, AlState to) {
    // The bootloader applies a firmware received in BOOT when it leaves BOOT (to INIT, the only way out).
    if (from == AlState::Boot && to == AlState::Init && pending_revision_) {
        slave_.apply_firmware_revision(*pending_revision_);
        ++counters_.firmware_updates;
    }
    if (from == AlState::Boot) pending_revision_.reset();
}

std::size_t attach_foe(esc::Segment& seg, const FoeOptions& options) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < seg.size(); ++i) {
        auto& s = seg.slave(i);
        const auto& d = s.description();
        if (!(d.mailbox_protocols & device::mbx_proto::FoE) || !d.sm_of_type(device::SmType::MailboxOut))
            continue;
        std::string dir;
        if (!options.dir.empty())
            dir = (std::filesystem::path(options.dir) / ("slave-" + std::to_string(i))).string();
        s.add_mailbox_protocol(std::make_unique<FoeServer>(s, options, std::move(dir)));
        ++n;
    }
    return n;
}

FoeServer* foe_server(esc::Slave& slave) {
    return dynamic_cast<FoeServer*>(slave.mailbox_protocol(MailboxType::FoE));
}

}  // namespace vecat::foe
