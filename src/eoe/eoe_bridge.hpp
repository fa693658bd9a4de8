// The Ethernet sides of the EoE devices of a segment as TAP interfaces (vecat run --eoe-tap): one per
// device, PREFIX0, PREFIX1, ... in slave order, created in the namespace vecat runs in. Frames the master
// sends through EoE that are not for the device itself go out of its TAP; frames read from the TAP go to
// the master through EoE (subject to the device's address filter). The serve loop waits on the TAP
// descriptors beside its socket (net::SideChannel) and calls service() on its own thread.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "eoe/eoe_server.hpp"
#include "eoe/tap.hpp"
#include "esc/segment.hpp"
#include "net/side_channel.hpp"

namespace vecat::eoe {

class EoeBridge final : public net::SideChannel {
  public:
    // A TAP named prefix + N for the EoE server of each slave N that has one. Throws std::runtime_error
    // when a TAP cannot be made.
    EoeBridge(esc::Segment& seg, const std::string& prefix);
    ~EoeBridge() override;

    std::span<const int> fds() const override { return fds_; }
    void service(std::uint64_t now_ns) override;

    std::size_t size() const { return ports_.size(); }
    const Tap& tap(std::size_t i) const { return *ports_[i]->tap; }
    std::uint64_t write_errors() const;

  private:
    struct Port final : EthernetPort {
        std::unique_ptr<Tap> tap;
        EoeServer* server = nullptr;
        std::uint64_t write_errors = 0;
        void send(ConstBytes frame) override {
            if (!tap->write(frame)) ++write_errors;
        }
    };
    std::vector<std::unique_ptr<Port>> ports_;
    std::vector<int> fds_;
    std::array<std::uint8_t, 2048> buf_{};
};

}  // namespace vecat::eoe
