// Writes the seed corpora of the fuzz targets, produced by the project's own code: the frames and mailbox
// messages the project master sends to an in-process drive (start-up to OP, SDO transfers of every kind,
// SDO information), SII interface sequences, and the ESI file of the default drive, whole and cut down.
//   vecat_fuzz_corpus DIR   ->  DIR/frame, DIR/mailbox, DIR/sii, DIR/esi
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "cia402/drive.hpp"
#include "esi/esi_writer.hpp"
#include "fuzz_support.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "net/pcapng_writer.hpp"
#include "net/recording_link.hpp"
#include "protocol/cia402_objects.hpp"
#include "serve/in_process_link.hpp"

namespace obj = vecat::protocol::obj;

using namespace vecat;
namespace fs = std::filesystem;

namespace {

using Seed = std::vector<std::uint8_t>;

// Records every frame the master sends.
class RecordingLink final : public net::Link {
  public:
    explicit RecordingLink(esc::Segment& seg) : inner_(seg) {}
    bool send(ConstBytes f) override {
        frames.emplace_back(f.begin(), f.end());
        return inner_.send(f);
    }
    long receive(Bytes b, std::int64_t t) override { return inner_.receive(b, t); }
    std::vector<Seed> frames;

  private:
    net::InProcessLink inner_;
};

void write_seed(const fs::path& dir, unsigned& n, const Seed& s) {
    fs::create_directories(dir);
    char name[32];
    std::snprintf(name, sizeof name, "seed-%04u", n++);
    std::ofstream(dir / name, std::ios::binary)
        .write(reinterpret_cast<const char*>(s.data()), static_cast<std::streamsize>(s.size()));
}

// Frame target: runs of consecutive frames, each length-prefixed.
void frame_seeds(const fs::path& dir, const std::vector<Seed>& frames, unsigned& n) {
    constexpr std::size_t kRun = 12;
    for (std::size_t i = 0; i < frames.size(); i += kRun) {
        Seed s;
        for (std::size_t k = i; k < std::min(frames.size(), i + kRun); ++k)
            fuzz::put_chunk(s, frames[k]);
        write_seed(dir, n, s);
    }
}

// Mailbox target: the SM0 writes (opcode 0) and SM1 reads (opcode 2) of the recorded frames.
Seed mailbox_seed(const std::vector<Seed>& frames, const device::DeviceDescription& d) {
    const auto sm0 = d.sync_managers.at(0), sm1 = d.sync_managers.at(1);
    Seed s;
    for (const auto& f : frames) {
        const auto pf = protocol::parse_frame(f);
        if (pf.error != protocol::FrameError::None) continue;
        for (std::size_t i = 0; i < pf.count; ++i) {
            const std::uint8_t* h = f.data() + pf.offsets[i];
            const auto cmd = static_cast<protocol::Command>(h[0]);
            const std::uint16_t ado = ld_le16(h + 4);
            const std::size_t len = ld_le16(h + 6) & 0x07FF;
            if (cmd == protocol::Command::FPWR && ado == sm0.start && len == sm0.length) {
                // Only the message itself: the fuzz target pads it to the SM length.
                const std::size_t used =
                    std::min<std::size_t>(len, protocol::kMailboxHeaderSize + ld_le16(h + 10));
                s.push_back(0);
                fuzz::put_chunk(s, ConstBytes(h + protocol::kDatagramHeaderSize, used));
            } else if (cmd == protocol::Command::FPRD && ado == sm1.start && len == sm1.length) {
                s.push_back(2);
            }
        }
    }
    return s;
}

void sii_seeds(const fs::path& dir, unsigned& n) {
    // Read commands over the header, the categories and past the end; a word write with and without write
    // enable; a reload; a parse.
    const std::vector<std::uint32_t> words = {0x0000, 0x0008, 0x0018, 0x0040, 0x0050, 0x07FE, 0x0800, 0xFFFF};
    Seed s;
    for (auto w : words) {
        s.insert(s.end(), {2, static_cast<std::uint8_t>(w), static_cast<std::uint8_t>(w >> 8), 0});
    }
    write_seed(dir, n, s);
    write_seed(dir, n, Seed{3, 1, 0x04, 0x00, 0x34, 0x12, 4, 5, 2, 0x04, 0x00, 0});
    write_seed(dir, n, Seed{3, 0, 0x07, 0x00, 0x00, 0x00, 4, 2, 0x00, 0x00, 0, 5});  // bad checksum
    write_seed(dir, n, Seed{0, 2, 2, 0x00, 0x01, 1, 0, 16, 4});
}

// The default drive cut down to one RxPDO and one TxPDO of two entries each, the objects they map and one
// object of each other kind (a string, an ARRAY, a RECORD): every construct of the ESI file in a few kB.
// Mutating the whole drive's file (180 kB) costs the fuzzer ten times as much per input for the same code.
device::DeviceDescription compact_drive(device::DeviceDescription d) {
    d.rx_pdos.resize(std::min<std::size_t>(d.rx_pdos.size(), 1));
    d.tx_pdos.resize(std::min<std::size_t>(d.tx_pdos.size(), 1));
    std::vector<std::uint16_t> keep;
    for (auto* pdos : {&d.rx_pdos, &d.tx_pdos})
        for (auto& p : *pdos) {
            p.entries.resize(std::min<std::size_t>(p.entries.size(), 2));
            p.capacity = static_cast<std::uint8_t>(p.entries.size());
            for (const auto& e : p.entries)
                keep.push_back(e.index);
        }
    bool string = false, array = false, record = false;
    std::vector<device::ObjectDescription> objects;
    for (auto& o : d.objects) {
        bool take = std::find(keep.begin(), keep.end(), o.index) != keep.end();
        if (!take && !string && o.code == device::ObjectCode::Var && device::is_variable_length(o.type))
            take = string = true;
        if (!take && !array && o.code == device::ObjectCode::Array) take = array = true;
        if (!take && !record && o.code == device::ObjectCode::Record) take = record = true;
        if (take) objects.push_back(std::move(o));
    }
    d.objects = std::move(objects);
    return d;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s OUTPUT_DIR\n", argv[0]);
        return 2;
    }
    const fs::path out = argv[1];
    const auto dev = device::default_drive();
    auto seg = cia402::make_drive_segment(dev, 2);
    RecordingLink link(*seg);
    master::Master m(link);
    std::string why;
    if (!m.startup(protocol::AlState::PreOp, &why)) {
        std::fprintf(stderr, "start-up failed: %s\n", why.c_str());
        return 1;
    }
    unsigned nf = 0, nm = 0, ns = 0, ne = 0;
    frame_seeds(out / "frame", link.frames, nf);

    // One mailbox seed per CoE exchange (its frames also feed the frame target).
    master::CoeClient coe(m, m.slaves().at(0).station);
    const std::vector<std::function<void()>> exchanges = {
        [&] { coe.upload(0x1018, 1); },
        [&] { coe.upload(0x1008, 0); },
        [&] { coe.upload(0x5555, 0); },
        [&] { coe.upload(0x1C12, 0, true); },
        [&] { coe.upload(0x1A00, 0, true); },
        [&] { coe.download_value<std::int8_t>(obj::modes_of_operation.index, 0, 8); },
        [&] {
            const std::uint8_t v[4] = {1, 2, 3, 4};
            coe.download(0x2000, 1, ConstBytes(v, 4), false, master::CoeClient::Transfer::Normal);
        },
        [&] {
            const std::uint8_t v[4] = {0x10, 0, 0, 0};
            coe.download(0x2000, 2, ConstBytes(v, 4), false, master::CoeClient::Transfer::Segmented);
        },
        [&] {
            const std::uint8_t v[5] = {2, 0x00, 0x16, 0x01, 0x16};
            coe.download(0x1C12, 0, ConstBytes(v, 5), true);
        },
        [&] { coe.od_list(protocol::sdo_info::ListAll); },
        [&] { coe.od_list(protocol::sdo_info::ListLengths); },
        [&] { coe.object_description(0x1018); },
        [&] { coe.entry_description(obj::controlword.index, 0, 0x78); },
        [&] { coe.entry_description(0x1018, 9, 0x78); },
    };
    for (const auto& x : exchanges) {
        link.frames.clear();
        x();
        write_seed(out / "mailbox", nm, mailbox_seed(link.frames, dev));
        frame_seeds(out / "frame", link.frames, nf);
    }
    link.frames.clear();
    if (m.request_state(protocol::AlState::SafeOp) && m.request_state(protocol::AlState::Op))
        for (int i = 0; i < 20; ++i)
            m.exchange_process_data();
    m.request_state(protocol::AlState::Init);
    frame_seeds(out / "frame", link.frames, nf);

    sii_seeds(out / "sii", ns);
    const std::string esi = esi::write_esi(dev);
    write_seed(out / "esi", ne, Seed(esi.begin(), esi.end()));
    const std::string small = esi::write_esi(compact_drive(dev));
    write_seed(out / "esi", ne, Seed(small.begin(), small.end()));
    // Capture target: a pcapng of the project master resetting one drive, giving it its address and reading
    // the start of its SII (both directions), short enough for the fuzzer's input size.
    {
        fs::create_directories(out / "capture");
        auto one = cia402::make_drive_segment(dev, 1);
        net::InProcessLink inner(*one);
        net::PcapngWriter w((out / "capture" / "seed-0000").string());
        net::RecordingLink rec(inner, w);
        master::Master m1(rec);
        m1.reset_slaves();
        m1.assign_station_addresses();
        for (std::uint32_t word = 0; word < 0x48; word += 2)
            m1.read_sii_dword(0x1001, word);
        w.flush();
    }
    std::printf("seeds: %u frame, %u mailbox, %u sii, %u esi, 1 capture in %s\n", nf, nm, ns, ne,
                out.c_str());
    return 0;
}
