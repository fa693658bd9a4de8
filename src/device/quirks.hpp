// Device quirks: what some real devices do less completely than vecat's drive, turned on per device (the
// network file's `quirks:`, `vecat run --quirk`) so that a master's test sees how its master copes. Each is
// what a kind of real device does (docs/network-file.md, "Quirks"). The description carries them (one
// source for the dictionary, the SII, the ESI and the firmware); apply_quirks() makes its flags agree.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace vecat::device {

struct DeviceDescription;

// SII categories a device may lack (ETG.2010 categories a master reads after the fixed words; real dumps
// lack them: the HBM ClipX and SOES devices have neither TxPDO/RxPDO nor DC); bits of Quirks::sii_without.
namespace sii_optional {
inline constexpr std::uint8_t Strings = 0x01;  // no Strings category: names and groups unknown (index 0)
inline constexpr std::uint8_t Pdo = 0x02;      // no TxPDO/RxPDO categories: the mapping is only in CoE
inline constexpr std::uint8_t Dc = 0x04;       // no DC category: the DC modes only in the ESI
}  // namespace sii_optional

struct Quirks {
    // SDO information requests get the mailbox error "service not supported" (ETG.1000.4 Table 30); the
    // SII General category's CoE details and the ESI's CoE SdoInfo say the device has none (ETG.2010).
    bool no_sdo_info = false;
    // Complete access upload and download aborted with 0x06010000 "unsupported access to an object"
    // (ETG.1000.6 Table 41); CoE details bit 5 (ESI CompleteAccess) cleared.
    bool no_complete_access = false;
    // At most this many entries per PDO mapping object (0x16xx/0x1Axx have this many subindexes; 0: as the
    // device describes). Writing subindex 0 beyond it: 0x06090031 "value too high" (ETG.1000.6 Table 41).
    unsigned max_pdo_entries = 0;
    // Fixed PDOs: the device has its default PDOs only, mapping and assignment read-only (a write: 0x06010002
    // "attempt to write a read only object"); the PDOs fixed and mandatory in SII and ESI, CoE details
    // without PdoAssign and PdoConfig.
    bool fixed_pdos = false;
    // The reply to a mailbox request appears in the mailbox-in SyncManager only this long after the
    // request was taken (ns; 0: at the next firmware run). At most 500 ms: the device's own SDO server drops
    // a segmented transfer left alone for 1 s (coe::SdoServer::kSdoTimeoutNs), and a delay near it would
    // let it drop the transfer it is answering; masters give up after 700 ms (SOEM's EC_TIMEOUTRXM).
    std::uint64_t mailbox_delay_ns = 0;
    // Every Kth mailbox reply is lost on its way into the mailbox-in SyncManager (0: none); the master's
    // repeat request (ETG.1000.4 5.6.3) brings it back.
    unsigned mailbox_drop_every = 0;
    // SII categories left out (sii_optional bits).
    std::uint8_t sii_without = 0;
    // The initiate SDO download response carries the request's data field (bytes 4-7 of the SDO header)
    // where ETG.1000.6 5.6.2 has reserved bytes (vecat sends 0): a firmware that answers in the request's
    // buffer, as the EL3004 of ../shared/data/pcap does.
    bool sdo_download_echo = false;
    // The firmware opens the mailbox-in buffer as soon as the master has read the last message, writing its
    // first byte, and completes it when the next message is ready: between the two the master reads the
    // SyncManager status as 0x80, write buffer in use (ESC datasheet section II 0x0805 bit 7), where an ESC
    // whose firmware writes each message at once shows 0x02, interrupt read. The EL3004 of
    // ../shared/data/pcap does this.
    bool mailbox_open_early = false;

    bool any() const {
        return no_sdo_info || no_complete_access || max_pdo_entries || fixed_pdos || mailbox_delay_ns ||
               mailbox_drop_every || sii_without || sdo_download_echo || mailbox_open_early;
    }
    friend bool operator==(const Quirks&, const Quirks&) = default;
};

// One quirk as written in a network file's list and on the command line: `no_sdo_info`,
// `no_complete_access`, `fixed_pdos`, `sdo_download_echo`, `mailbox_open_early`, `max_pdo_entries=N`
// (1..254), `mailbox_delay_ms=T` (0..500, fractions allowed), `mailbox_drop_every=K` (2..1000),
// `sii_without=strings+pdo+dc` (any of them). Adds it to q; returns "" or what is wrong with it.
std::string parse_quirk(std::string_view text, Quirks& q);

// The quirks of q as parse_quirk reads them, joined by ", " ("" for none): what vecat network check shows.
std::string to_string(const Quirks& q);

// The names of the quirks, for messages and --help.
inline constexpr std::string_view kQuirkNames =
    "no_sdo_info, no_complete_access, fixed_pdos, sdo_download_echo, mailbox_open_early, max_pdo_entries=N, "
    "mailbox_delay_ms=T, mailbox_drop_every=K, sii_without=strings+pdo+dc";

// Sets d.quirks to q and makes the description agree with them: the CoE details flags (SII General
// category, ESI CoE element), the PDOs (fixed, capacity). Returns "" or why the device cannot have them
// (a default mapping longer than max_pdo_entries, a CoE quirk on a device without CoE).
std::string apply_quirks(DeviceDescription& d, const Quirks& q);

}  // namespace vecat::device
