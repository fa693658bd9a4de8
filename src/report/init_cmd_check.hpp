// The master against an ENI's InitCmds (ETG.2100 Slave/InitCmds): the register writes the ENI says the master
// sends to each slave at each AL transition, compared with the writes the master does send. A net::
// FrameObserver next to the segment, as the report's other checks.
//
// The writes a master sends to a slave between two state requests (AL control 0x0120) belong to the
// transition the second request starts (from the slave's state then to the state requested): the ENI lists
// the commands of transition IP before the master requests PREOP. At each request the check compares, byte
// for byte on the slave's registers, what the ENI's commands of that transition write with what the master
// wrote: an ENI command with a byte the master did not write (or wrote otherwise) is missing, a master's
// write with a byte no ENI command of the transition writes so is extra.
//
// Compared: physical writes (APWR, FPWR, BWR, APRW, FPRW, BRW) to the register space below 0x1000 other
// than AL control itself (the state requests are the master's to make) and the SII interface 0x0500-0x050F
// (reading the SII is no configuration). A byte counts with every value written to it between the two
// requests. Not compared: reads and their validation (Cnt, Validate), logical commands, mailbox traffic and
// the CoE InitCmds (SDOs).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "esc/segment.hpp"
#include "net/frame_observer.hpp"
#include "network/eni.hpp"
#include "network/eni_network.hpp"

namespace vecat::report {

// An AL transition: from and to as AL states (1 INIT, 2 PREOP, 3 BOOT, 4 SAFEOP, 8 OP).
struct Transition {
    std::uint8_t from = 0, to = 0;
    friend bool operator==(const Transition&, const Transition&) = default;
};
std::string to_string(Transition t);  // "IP", "PS"...

// One configuration command the master is expected to send to the slave at a position.
struct ExpectedWrite {
    std::size_t slave = 0;  // position on the line
    std::vector<Transition> transitions;
    std::uint16_t ado = 0;
    std::vector<std::uint8_t> data;
    std::string label;  // where the ENI has it ("FILE:LINE: PATH (comment)")
};

struct CommandDifference {
    bool missing = false;  // expected and not sent; else sent and not expected
    std::size_t slave = 0;
    Transition transition;
    std::string what;
    std::uint64_t count = 1;  // times it happened
};

// The ENI's register writes, per slave position (n: the network made from the ENI, for the positions).
std::vector<ExpectedWrite> expected_writes(const network::Eni& eni, const network::EniNetwork& n);

class InitCmdCheck final : public net::FrameObserver {
  public:
    InitCmdCheck(const esc::Segment& seg, std::vector<ExpectedWrite> expected);

    void on_request(ConstBytes frame, std::uint64_t now_ns) override;
    void on_reply(ConstBytes, std::uint64_t) override {}

    const std::vector<CommandDifference>& differences() const { return differences_; }
    // What the master wrote, per transition, as expected writes (to make an expectation from a master).
    const std::vector<ExpectedWrite>& observed() const { return observed_; }
    // One line per difference, and a last line with the count.
    std::string summary() const;

  private:
    struct Write {
        std::uint16_t ado = 0;
        std::vector<std::uint8_t> data;
        std::uint8_t command = 0;
    };
    void on_write(std::size_t slave, const Write& w);
    void on_state_request(std::size_t slave, std::uint8_t requested);
    void report(bool missing, std::size_t slave, Transition t, std::string what);

    const esc::Segment& seg_;
    std::vector<ExpectedWrite> expected_;
    std::vector<std::vector<Write>> pending_;  // per slave, since its last state request
    std::vector<CommandDifference> differences_;
    std::vector<ExpectedWrite> observed_;
    std::vector<std::uint8_t> buf_;
};

}  // namespace vecat::report
