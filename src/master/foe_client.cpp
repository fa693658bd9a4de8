#include "master/foe_client.hpp"

#include <algorithm>
#include <array>

#include "protocol/registers.hpp"
#include "protocol/sync_manager.hpp"

namespace vecat::master {

using namespace protocol;

FoeClient::FoeClient(Master& m, std::uint16_t station) : mbx_(m, station) {}

std::optional<FoeMessage> FoeClient::answer(FoeResult& r) {
    last_ = mbx_.receive(timeout);
    if (!last_) {
        r.transport_ok = false;
        return std::nullopt;
    }
    if (last_->header.type == static_cast<std::uint8_t>(MailboxType::Error)) {
        if (last_->payload.size() >= kMailboxErrorSize)
            r.mailbox_error = static_cast<MailboxError>(ld_le16(last_->payload.data() + 2));
        else
            r.unexpected = true;
        return std::nullopt;
    }
    if (last_->header.type != static_cast<std::uint8_t>(MailboxType::FoE)) {
        r.unexpected = true;
        return std::nullopt;
    }
    auto msg = parse_foe(last_->payload);
    if (!msg) {
        r.unexpected = true;
        return std::nullopt;
    }
    if (msg->op == FoeOpCode::Error) {
        r.error = static_cast<FoeError>(msg->value);
        r.error_text = std::string(msg->text());
        return std::nullopt;
    }
    return msg;
}

std::optional<FoeMessage> FoeClient::exchange(ConstBytes request, FoeResult& r) {
    if (!mbx_.send(MailboxType::FoE, request, mbx_.next_counter())) {
        r.transport_ok = false;
        return std::nullopt;
    }
    return answer(r);
}

FoeResult FoeClient::read(std::string_view name, std::uint32_t password, std::size_t max_size) {
    FoeResult r;
    r.transport_ok = true;
    const std::size_t full = foe_data_capacity(mbx_.mailbox_size_in());
    std::vector<std::uint8_t> buf(kFoeHeaderSize + std::min(name.size(), kFoeMaxFileName));
    const std::size_t n = write_foe_request(buf, FoeOpCode::Read, password, name.substr(0, kFoeMaxFileName));
    auto msg = exchange(ConstBytes(buf.data(), n), r);
    std::uint32_t expected = 1;
    std::array<std::uint8_t, kFoeHeaderSize> ack{};
    while (msg) {
        if (msg->op == FoeOpCode::Busy) {  // the slave is not ready yet: wait for its data
            if (++r.busy > max_busy) break;
            msg = answer(r);
            continue;
        }
        if (msg->op != FoeOpCode::Data || msg->value != expected ||
            r.data.size() + msg->tail.size() > max_size) {
            r.unexpected = true;
            break;
        }
        r.data.insert(r.data.end(), msg->tail.begin(), msg->tail.end());
        ++r.packets;
        const bool last = msg->tail.size() < full;
        write_foe_ack(ack, expected);
        if (last) {
            // The acknowledge of the last packet ends the read; the slave does not answer it.
            if (!mbx_.send(MailboxType::FoE, ack, mbx_.next_counter())) r.transport_ok = false;
            break;
        }
        ++expected;
        msg = exchange(ack, r);
    }
    return r;
}

FoeResult FoeClient::write(std::string_view name, ConstBytes data, std::uint32_t password) {
    FoeResult r;
    r.transport_ok = true;
    const std::size_t full = foe_data_capacity(mbx_.mailbox_size_out());
    if (full == 0) {
        r.transport_ok = false;
        return r;
    }
    std::vector<std::uint8_t> buf(kFoeHeaderSize + std::max(full, std::min(name.size(), kFoeMaxFileName)));
    const std::size_t n = write_foe_request(buf, FoeOpCode::Write, password, name.substr(0, kFoeMaxFileName));
    auto msg = exchange(ConstBytes(buf.data(), n), r);
    if (!msg) return r;
    if (msg->op != FoeOpCode::Ack || msg->value != 0) {
        r.unexpected = true;
        return r;
    }
    // ETG.1000.6 5.8.4: packets of a full mailbox; the file ends with a shorter one (empty if need be).
    std::size_t offset = 0;
    std::uint32_t packet = 1;
    while (true) {
        const std::size_t len = std::min(full, data.size() - offset);
        const std::size_t m = write_foe_data(buf, packet, data.subspan(offset, len));
        msg = exchange(ConstBytes(buf.data(), m), r);
        if (!msg) return r;
        if (msg->op == FoeOpCode::Busy) {  // not taken: send the same packet again
            if (++r.busy > max_busy) {
                r.unexpected = true;
                return r;
            }
            continue;
        }
        if (msg->op != FoeOpCode::Ack || msg->value != packet) {
            r.unexpected = true;
            return r;
        }
        ++r.packets;
        offset += len;
        if (len < full) return r;
        ++packet;
    }
}

bool configure_boot_mailbox(Master& m, const SlaveInfo& s) {
    const auto& sii = s.sii;
    if (!sii.boot_rx_mbx_size || !sii.boot_tx_mbx_size || sii.sync_managers.size() < 2) return false;
    const std::uint16_t start[2] = {sii.boot_rx_mbx_offset, sii.boot_tx_mbx_offset};
    const std::uint16_t len[2] = {sii.boot_rx_mbx_size, sii.boot_tx_mbx_size};
    for (unsigned i = 0; i < 2; ++i) {
        // Disabled first: the ESC keeps start, length and control while the SM is enabled (IgH clears the
        // SyncManagers in INIT; SOEM pull request #483 added the same to firm_update).
        std::uint8_t disabled = 0;
        const auto off =
            m.fpwr(s.station, static_cast<std::uint16_t>(sm_addr(i) + sm::Activate), Bytes(&disabled, 1));
        if (!off || *off != 1) return false;
        std::uint8_t b[SmConfig::kSize];
        SmConfig::master(start[i], len[i], sii.sync_managers[i].control).pack(b);
        const auto w = m.fpwr(s.station, sm_addr(i), b);
        if (!w || *w != 1) return false;
    }
    return true;
}

}  // namespace vecat::master
