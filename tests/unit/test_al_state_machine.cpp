// The AL state machine: every row of the transition table, error indication and acknowledge, the
// configuration checks and their AL status codes, the watchdog.
#include <gtest/gtest.h>

#include <array>

#include "protocol/cia402_objects.hpp"
#include "test_support.hpp"

namespace obj = vecat::protocol::obj;

using namespace vecat;
using namespace vecat::test;
using protocol::AlState;
using protocol::AlStatusCode;

namespace {

struct Expect {
    AlState from, to;
    AlState result;
    AlStatusCode code;  // NoError: no error indication
};

void reach(Bench& b, AlState s) {
    std::string why;
    const AlState via = s == AlState::Init ? AlState::Init : s;
    ASSERT_TRUE(b.master.startup(via, &why)) << why;
}

master::AlStatusReading request(Bench& b, std::uint16_t value) {
    const auto st = b.master.slaves()[0].station;
    EXPECT_TRUE(b.master.write16(st, 0x0120, value));
    return b.master.read_al_status(st);
}

class Transition : public ::testing::TestWithParam<Expect> {};

}  // namespace

TEST_P(Transition, RowOfTheTable) {
    const auto& e = GetParam();
    Bench b(1);
    reach(b, e.from);
    if (e.from == AlState::Init) {
        ASSERT_TRUE(b.master.configure_mailboxes());
    }
    if (e.from == AlState::PreOp && e.to == AlState::SafeOp) {
        ASSERT_TRUE(b.master.configure_process_data());
    }
    if (e.to == AlState::Op) b.master.exchange_process_data();
    const auto r = request(b, static_cast<std::uint16_t>(e.to));
    ASSERT_TRUE(r.ok);
    EXPECT_EQ(r.state(), e.result);
    EXPECT_EQ(r.error(), e.code != AlStatusCode::NoError);
    EXPECT_EQ(r.code, static_cast<std::uint16_t>(e.code));
    EXPECT_EQ(b.slave().state(), e.result);
}

using S = AlState;
using C = AlStatusCode;
INSTANTIATE_TEST_SUITE_P(
    AllRows, Transition,
    ::testing::Values(
        Expect{S::Init, S::Init, S::Init, C::NoError}, Expect{S::Init, S::PreOp, S::PreOp, C::NoError},
        // The drive's bootstrap mailbox is its standard mailbox (test_foe.cpp: the other cases).
        Expect{S::Init, S::Boot, S::Boot, C::NoError},
        Expect{S::Init, S::SafeOp, S::Init, C::InvalidRequestedStateChange},
        Expect{S::Init, S::Op, S::Init, C::InvalidRequestedStateChange},
        Expect{S::PreOp, S::Init, S::Init, C::NoError}, Expect{S::PreOp, S::PreOp, S::PreOp, C::NoError},
        Expect{S::PreOp, S::Boot, S::PreOp, C::InvalidRequestedStateChange},
        Expect{S::PreOp, S::SafeOp, S::SafeOp, C::NoError},
        Expect{S::PreOp, S::Op, S::PreOp, C::InvalidRequestedStateChange},
        Expect{S::SafeOp, S::Init, S::Init, C::NoError}, Expect{S::SafeOp, S::PreOp, S::PreOp, C::NoError},
        Expect{S::SafeOp, S::Boot, S::SafeOp, C::InvalidRequestedStateChange},
        Expect{S::SafeOp, S::SafeOp, S::SafeOp, C::NoError}, Expect{S::SafeOp, S::Op, S::Op, C::NoError},
        Expect{S::Op, S::Init, S::Init, C::NoError}, Expect{S::Op, S::PreOp, S::PreOp, C::NoError},
        Expect{S::Op, S::Boot, S::SafeOp, C::InvalidRequestedStateChange},
        Expect{S::Op, S::SafeOp, S::SafeOp, C::NoError}, Expect{S::Op, S::Op, S::Op, C::NoError}));

TEST(AlTable, MatchesTheSpecification) {
    using A = esc::AlAction;
    EXPECT_EQ(esc::al_transition(S::Init, S::PreOp), A::CheckMailbox);
    EXPECT_EQ(esc::al_transition(S::PreOp, S::SafeOp), A::CheckProcessData);
    EXPECT_EQ(esc::al_transition(S::SafeOp, S::Op), A::CheckOutputs);
    EXPECT_EQ(esc::al_transition(S::Boot, S::PreOp), A::Refuse);
    EXPECT_EQ(esc::al_transition(S::Boot, S::Init), A::Down);
    EXPECT_EQ(esc::al_transition(S::Op, S::SafeOp), A::Down);
}

TEST(AlStateMachine, UnknownStateIsRefused) {
    for (std::uint16_t v : std::initializer_list<std::uint16_t>{0x00, 0x05, 0x06, 0x07, 0x09, 0x0F}) {
        Bench b(1);
        reach(b, S::PreOp);
        const auto r = request(b, v);
        EXPECT_EQ(r.state(), S::PreOp) << v;
        EXPECT_TRUE(r.error());
        EXPECT_EQ(r.code, 0x0012);
    }
}

TEST(AlStateMachine, ErrorNeedsAcknowledgeExceptForInit) {
    Bench b(1);
    reach(b, S::PreOp);
    request(b, static_cast<std::uint16_t>(S::Op));  // refused: error indication set
    auto r = request(b, static_cast<std::uint16_t>(S::PreOp));
    EXPECT_TRUE(r.error());  // ignored without acknowledge
    EXPECT_EQ(r.code, 0x0011);
    r = request(b, static_cast<std::uint16_t>(S::PreOp) | 0x10);
    EXPECT_FALSE(r.error());
    EXPECT_EQ(r.code, 0);
    EXPECT_EQ(r.state(), S::PreOp);
    request(b, static_cast<std::uint16_t>(S::Op));
    r = request(b, static_cast<std::uint16_t>(S::Init));  // INIT is obeyed without acknowledge
    EXPECT_EQ(r.state(), S::Init);
    EXPECT_FALSE(r.error());
}

TEST(AlStateMachine, InvalidMailboxConfigurationIsRefused) {
    Bench b(1);
    reach(b, S::Init);
    const auto st = b.master.slaves()[0].station;
    ASSERT_TRUE(b.master.configure_mailboxes());
    ASSERT_TRUE(b.master.write16(st, protocol::sm_addr(0) + 2, 0x0080));  // locked: SM0 is enabled
    ASSERT_TRUE(b.master.write8(st, protocol::sm_addr(0) + 6, 0));        // disable SM0
    ASSERT_TRUE(b.master.write16(st, protocol::sm_addr(0) + 2, 0x0080));  // wrong length
    ASSERT_TRUE(b.master.write8(st, protocol::sm_addr(0) + 6, 1));
    const auto r = request(b, static_cast<std::uint16_t>(S::PreOp));
    EXPECT_EQ(r.state(), S::Init);
    EXPECT_EQ(r.code, 0x0016);
}

TEST(AlStateMachine, WrongProcessDataSyncManagersAreRefused) {
    for (unsigned smi : {2u, 3u}) {
        Bench b(1);
        reach(b, S::PreOp);
        ASSERT_TRUE(b.master.configure_process_data());
        const auto st = b.master.slaves()[0].station;
        ASSERT_TRUE(b.master.write8(st, static_cast<std::uint16_t>(protocol::sm_addr(smi) + 6), 0));
        ASSERT_TRUE(b.master.write16(st, static_cast<std::uint16_t>(protocol::sm_addr(smi) + 2), 3));
        ASSERT_TRUE(b.master.write8(st, static_cast<std::uint16_t>(protocol::sm_addr(smi) + 6), 1));
        const auto r = request(b, static_cast<std::uint16_t>(S::SafeOp));
        EXPECT_EQ(r.state(), S::PreOp);
        EXPECT_EQ(r.code, smi == 2 ? 0x001D : 0x001E);
    }
}

// SAFEOP reached without any process data exchange yet (the master's request_state sends process data).
void reach_safeop_silently(Bench& b) {
    reach(b, S::PreOp);
    ASSERT_TRUE(b.master.configure_process_data());
    ASSERT_EQ(request(b, static_cast<std::uint16_t>(S::SafeOp)).state(), S::SafeOp);
}

TEST(AlStateMachine, OpWaitsForValidOutputs) {
    Bench b(1);
    reach_safeop_silently(b);
    auto r = request(b, static_cast<std::uint16_t>(S::Op));
    EXPECT_EQ(r.state(), S::SafeOp);  // pending, no error yet
    EXPECT_FALSE(r.error());
    b.master.exchange_process_data();
    r = b.master.read_al_status(b.master.slaves()[0].station);
    EXPECT_EQ(r.state(), S::Op);
}

TEST(AlStateMachine, NoOutputsWithinTheTimeoutIsRefused) {
    Bench b(1);
    reach_safeop_silently(b);
    request(b, static_cast<std::uint16_t>(S::Op));
    b.advance(esc::Slave::kOutputsValidTimeoutNs + 1'000'000);
    const auto r = b.master.read_al_status(b.master.slaves()[0].station);
    EXPECT_EQ(r.state(), S::SafeOp);
    EXPECT_EQ(r.code, 0x0019);
}

TEST(AlStateMachine, ProcessDataWatchdogDropsToSafeOp) {
    Bench b(1);
    reach(b, S::Op);
    auto out = b.master.outputs(0);
    out[0] = 0x0F;  // controlword, the first object of RxPDO 0x1600
    b.master.exchange_process_data();
    auto& controlword = *b.od().find(obj::controlword);
    EXPECT_EQ(controlword.get<std::uint16_t>(), 0x0F);
    b.advance(50'000'000);  // 50 ms: within the 100 ms default
    EXPECT_EQ(b.slave().state(), S::Op);
    b.advance(60'000'000);
    EXPECT_EQ(b.slave().state(), S::SafeOp);
    EXPECT_EQ(b.slave().status_code(), AlStatusCode::SyncManagerWatchdog);
    EXPECT_EQ(controlword.get<std::uint16_t>(), 0);  // safe state
    EXPECT_EQ(b.escx().peek(0x0440) & 1, 0);
    EXPECT_EQ(b.escx().peek(0x0442), 1);
}

// The master sets the watchdog's time: 0x0420 x (0x0400 + 2) x 40 ns (ESC datasheet section II), here
// 20 x (498 + 2) x 40 ns = 400 us, written after the default; it expires then, not after 100 ms.
TEST(AlStateMachine, TheProcessDataWatchdogExpiresAtTheTimeTheMasterWrote) {
    Bench b(1);
    reach(b, S::Op);
    const auto st = b.master.slaves()[0].station;
    ASSERT_TRUE(b.master.write16(st, 0x0400, 498));
    ASSERT_TRUE(b.master.write16(st, 0x0420, 20));
    b.master.outputs(0)[0] = 0x0F;
    b.master.exchange_process_data();
    ASSERT_EQ(b.slave().state(), S::Op);
    b.advance(300'000);
    EXPECT_EQ(b.slave().state(), S::Op);
    b.advance(200'000);
    EXPECT_EQ(b.slave().state(), S::SafeOp);
    EXPECT_EQ(b.slave().status_code(), AlStatusCode::SyncManagerWatchdog);
}

// The watchdog expires at its time, also when no tick ran since and the next frame only writes: the slave
// catches up with its deadline before that frame retriggers the watchdog (Segment::catch_up_deadlines).
TEST(AlStateMachine, AWatchdogDueBeforeAWriteOnlyFrameExpiresBeforeTheFrameRetriggersIt) {
    Bench b(1);
    reach(b, S::Op);
    b.master.outputs(0)[0] = 0x0F;
    b.master.exchange_process_data();
    ASSERT_EQ(b.slave().state(), S::Op);
    // 150 ms later (100 ms default watchdog), no tick in between: a frame writes SM2's buffer only.
    b.now += 150'000'000;
    b.link.set_time(b.now);
    const std::uint16_t sm2 = ld_le16(std::array{b.escx().peek(0x0810), b.escx().peek(0x0811)}.data());
    std::vector<std::uint8_t> outputs(b.master.outputs(0).begin(), b.master.outputs(0).end());
    ASSERT_EQ(b.master.fpwr(b.master.slaves()[0].station, sm2, outputs).value(), 1);
    EXPECT_EQ(b.slave().state(), S::SafeOp);
    EXPECT_EQ(b.slave().status_code(), AlStatusCode::SyncManagerWatchdog);
    EXPECT_EQ(b.escx().peek(0x0442), 1);
}

TEST(AlStateMachine, InputsValidInSafeOpOutputsAppliedOnlyInOp) {
    Bench b(1);
    reach(b, S::SafeOp);
    b.od().find(obj::statusword)->set(std::uint16_t{0x5A});  // statusword, first in TxPDO 0x1A00
    auto& controlword = *b.od().find(obj::controlword);
    b.master.outputs(0)[0] = 0x77;
    b.master.exchange_process_data();
    b.master.exchange_process_data();
    EXPECT_EQ(b.master.inputs(0)[0], 0x5A);
    EXPECT_EQ(controlword.get<std::uint16_t>(), 0);
    ASSERT_TRUE(b.master.request_state(S::Op));
    b.master.exchange_process_data();
    EXPECT_EQ(controlword.get<std::uint16_t>(), 0x77);
}

TEST(Mailbox, UnsupportedProtocolGetsAMailboxError) {
    Bench b(1);
    reach(b, S::PreOp);
    const auto st = b.master.slaves()[0].station;
    std::vector<std::uint8_t> req(246, 0);
    st_le16(req.data(), 10);
    req[5] = 0x14;  // FoE (not served by this device), counter 1
    ASSERT_EQ(b.master.fpwr(st, 0x1800, req).value(), 1);
    std::vector<std::uint8_t> rep(246, 0);
    ASSERT_EQ(b.master.fprd(st, 0x18F6, rep).value(), 1);
    EXPECT_EQ(rep[5] & 0x0F, 0x00);                        // mailbox error reply
    EXPECT_EQ(ld_le16(rep.data() + 6), 0x0001);            // service
    EXPECT_EQ(ld_le16(rep.data() + 8), 0x0002);            // unsupported protocol
    ASSERT_EQ(b.master.fpwr(st, 0x1800, req).value(), 1);  // same counter again: not executed twice
    EXPECT_EQ(b.slave().counters().mailbox_duplicates, 1u);
    EXPECT_EQ(b.master.fprd(st, 0x18F6, rep).value(), 0);  // nothing to read
    // Repeat request: the last reply comes back.
    std::uint8_t act[1] = {0x03};
    ASSERT_EQ(b.master.fpwr(st, 0x080E, act).value(), 1);
    EXPECT_EQ(b.escx().peek(0x080F) & 0x02, 0x02);
    ASSERT_EQ(b.master.fprd(st, 0x18F6, rep).value(), 1);
    EXPECT_EQ(ld_le16(rep.data() + 8), 0x0002);
}

TEST(Mailbox, HeaderLengthPastTheMailboxIsAnError) {
    Bench b(1);
    reach(b, S::PreOp);
    const auto st = b.master.slaves()[0].station;
    std::vector<std::uint8_t> req(246, 0);
    st_le16(req.data(), 1000);
    req[5] = 0x03;
    ASSERT_EQ(b.master.fpwr(st, 0x1800, req).value(), 1);
    std::vector<std::uint8_t> rep(246, 0);
    ASSERT_EQ(b.master.fprd(st, 0x18F6, rep).value(), 1);
    EXPECT_EQ(ld_le16(rep.data() + 8), 0x0008);  // invalid size
}

// A slave that fell back to PREOP with an error deactivates its process data SyncManagers (0x0807); their
// areas stay locked (ESC datasheet section I 8.7), so the master's LRW no longer gets the full working
// counter and its check sees the fault.
TEST(AlStateMachine, ProcessDataOfASlaveLeftInPreOpWithAnErrorIsNotCounted) {
    Bench b(2);
    reach(b, S::SafeOp);
    EXPECT_EQ(b.master.exchange_process_data(), 6);  // LRW: 3 per slave
    b.slave(1).raise_error(C::SyncManagerWatchdog, S::PreOp);
    ASSERT_EQ(b.slave(1).state(), S::PreOp);
    EXPECT_EQ(b.master.exchange_process_data(), 3);  // only the first slave
}
