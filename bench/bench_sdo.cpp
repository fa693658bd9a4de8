// SDO round trips in-process: the project's master (CoeClient) against one drive in PREOP over an
// in-process link. Each SDO is a mailbox write, polls of SM1 and a mailbox read: several frames.
#include <benchmark/benchmark.h>

#include <memory>

#include "cia402/drive.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "protocol/cia402_objects.hpp"
#include "serve/in_process_link.hpp"

namespace {

using namespace vecat;
namespace obj = protocol::obj;

struct PreOpDrive {
    std::unique_ptr<esc::Segment> seg = cia402::make_drive_segment(device::default_drive(), 1);
    net::InProcessLink link{*seg};
    master::Master m{link};
    PreOpDrive() {
        link.set_time(1'000'000'000);
        if (!m.startup(protocol::AlState::PreOp)) throw std::runtime_error("start-up failed");
    }
};

// Expedited upload of the statusword (0x6041).
void BM_SdoUploadExpedited(benchmark::State& state) {
    PreOpDrive d;
    master::CoeClient c(d.m, d.m.slaves()[0].station);
    for (auto _ : state) {
        auto r = c.upload(obj::statusword.index, 0);
        if (!r.ok()) state.SkipWithError("upload failed");
        benchmark::DoNotOptimize(r.data.data());
    }
}
BENCHMARK(BM_SdoUploadExpedited);

// Expedited download of the profile velocity (0x6081, 4 bytes).
void BM_SdoDownloadExpedited(benchmark::State& state) {
    PreOpDrive d;
    master::CoeClient c(d.m, d.m.slaves()[0].station);
    std::uint32_t v = 1000;
    for (auto _ : state) {
        auto r = c.download_value(obj::profile_velocity.index, 0, v++);
        if (!r.ok()) state.SkipWithError("download failed");
    }
}
BENCHMARK(BM_SdoDownloadExpedited);

// Upload of the device name (0x1008, a string: normal transfer).
void BM_SdoUploadNormal(benchmark::State& state) {
    PreOpDrive d;
    master::CoeClient c(d.m, d.m.slaves()[0].station);
    for (auto _ : state) {
        auto r = c.upload(0x1008, 0);
        if (!r.ok()) state.SkipWithError("upload failed");
        benchmark::DoNotOptimize(r.data.data());
    }
}
BENCHMARK(BM_SdoUploadNormal);

// Complete access upload of the RxPDO mapping 0x1600 (several entries at once).
void BM_SdoUploadCompleteAccess(benchmark::State& state) {
    PreOpDrive d;
    master::CoeClient c(d.m, d.m.slaves()[0].station);
    for (auto _ : state) {
        auto r = c.upload(0x1600, 0, true);
        if (!r.ok()) state.SkipWithError("upload failed");
        benchmark::DoNotOptimize(r.data.data());
    }
}
BENCHMARK(BM_SdoUploadCompleteAccess);

}  // namespace
