// A link that writes every frame it carries to a pcapng file: what the master sent (outbound) and what came
// back (inbound), as a capture taken at the master's interface holds them, with the host's real time.
#pragma once

#include <cstdint>

#include "net/clock.hpp"
#include "net/link.hpp"
#include "net/pcapng_writer.hpp"

namespace vecat::net {

class RecordingLink final : public Link {
  public:
    RecordingLink(Link& inner, PcapngWriter& w) : inner_(inner), w_(w) {}
    bool send(ConstBytes f) override {
        w_.write(f, realtime_ns(), PcapngWriter::kOutbound);
        return inner_.send(f);
    }
    long receive(Bytes b, std::int64_t timeout_us) override {
        const long n = inner_.receive(b, timeout_us);
        if (n > 0)
            w_.write(ConstBytes(b.data(), static_cast<std::size_t>(n)), realtime_ns(),
                     PcapngWriter::kInbound);
        return n;
    }

  private:
    Link& inner_;
    PcapngWriter& w_;
};

}  // namespace vecat::net
