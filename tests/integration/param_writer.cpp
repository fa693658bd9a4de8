// Helper of the parameter kill test: one slave's dictionary with its parameter file in DIR; stores new
// parameter sets in a loop through 0x1010:01 "save" until it is killed. Each set writes the generation
// number g into all seven entries of 0x2000, so a mixed set would show differing values.
//   vecat_param_writer DIR
#include <cstdio>
#include <string>

#include "coe/coe_application.hpp"

using namespace vecat;

int main(int argc, char** argv) {
    if (argc != 2) return 2;
    coe::CoeApplication app(device::default_drive());
    const auto rep = app.attach_parameter_store(std::string(argv[1]) + "/slave-0.param");
    if (rep.load.status == coe::LoadStatus::Corrupt || rep.load.status == coe::LoadStatus::OtherDevice) {
        std::fprintf(stderr, "param_writer: %s\n", rep.load.detail.c_str());
        return 3;
    }
    auto& od = app.dictionary();
    std::uint32_t g = od.find(0x2000, 1)->get<std::uint32_t>();
    std::printf("started at generation %u\n", g);
    std::fflush(stdout);
    for (;;) {
        ++g;
        for (std::uint8_t sub = 1; sub <= 7; ++sub) {
            std::uint8_t v[4];
            st_le32(v, g);
            if (od.download(0x2000, sub, false, protocol::AlState::PreOp, ConstBytes(v, 4)) !=
                protocol::SdoAbort::None)
                return 4;
        }
        std::uint8_t save[4];
        st_le32(save, coe::kStoreSignature);
        if (od.download(0x1010, 1, false, protocol::AlState::PreOp, ConstBytes(save, 4)) !=
            protocol::SdoAbort::None)
            return 5;
    }
}
