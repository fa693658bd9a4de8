// The EtherCAT Network Information file (ENI, ETG.2100 "EtherCATConfig"), as configurators (TwinCAT, EC-
// Engineer, ...) export it, read into plain structures: per slave its identity (Info), its mailbox and the
// protocols it speaks (Mailbox), its process data (ProcessData: the SyncManagers Sm0..Sm3, RxPdo/TxPdo with
// their entries), the configuration commands the master sends at each AL transition (InitCmds, and the CoE
// InitCmds of the mailbox) and where it is cabled (PreviousPort). Element names are ETG.2100's; what the
// ENI holds beyond that (Cyclic, ProcessImage, DC, EoE...) is not read.
//
//   <EtherCATConfig><Config>
//     <Master><Info><Name>...</Name></Info></Master>
//     <Slave>
//       <Info><Name/><PhysAddr/><AutoIncAddr/><Physics/><VendorId/><ProductCode/><RevisionNo/><SerialNo/></Info>
//       <Mailbox><Send><Start/><Length/></Send><Recv><Start/><Length/></Recv><Protocol>CoE</Protocol>
//                <CoE><InitCmds><InitCmd>...</InitCmd></InitCmds></CoE></Mailbox>
//       <ProcessData><Sm2><Type>Outputs</Type><DefaultSize/><StartAddress/><ControlByte/><Enable/><Pdo/></Sm2>
//                    <RxPdo
//                    Sm="2"><Index/><Name/><Entry><Index/><SubIndex/><BitLen/><Name/><DataType/></Entry></RxPdo>
//       <InitCmds><InitCmd><Transition>IP</Transition><Cmd/><Adp/><Ado/><Data/><Cnt/></InitCmd></InitCmds>
//       <PreviousPort Selected="1"><Port>B</Port><PhysAddr/></PreviousPort>
//     </Slave>...
//
// Numbers are ETG.2100 HexDecValue ("#x1A00" or decimal; "0x1A00" is accepted as well); identifiers and
// addresses the schema types xs:int may be written negative (their bit pattern). Every refusal is an
// EniError "FILE:LINE: ELEMENT PATH: what is wrong" (the line of the element, from pugixml's offset).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "network/network_file.hpp"

namespace vecat::network {

class EniError : public NetworkFileError {
  public:
    using NetworkFileError::NetworkFileError;
};

// Where an element is: its line and its path ("Config/Slave[3]/Info/VendorId", 1-based indexes).
struct EniWhere {
    unsigned line = 0;
    std::string path;
};

// The AL transitions of ETG.2100 InitCmd/Transition ("IP", "PS", ...): one bit each.
enum class EniTransition : std::uint8_t { II, IP, PP, PI, PB, BI, IB, PS, SP, SI, SO, OS, OP, OI };
inline constexpr std::array<std::string_view, 14> kEniTransitionNames{
    "II", "IP", "PP", "PI", "PB", "BI", "IB", "PS", "SP", "SI", "SO", "OS", "OP", "OI"};
using EniTransitions = std::uint16_t;  // bit (1 << EniTransition)
constexpr EniTransitions bit(EniTransition t) noexcept {
    return static_cast<EniTransitions>(1u << static_cast<unsigned>(t));
}

// An ESC-level configuration command (ETG.2100 InitCmd of a slave or of the master).
struct EniInitCmd {
    EniWhere where;
    EniTransitions transitions = 0;
    bool before_slave = false;
    std::string comment;
    std::uint8_t cmd = 0;  // datagram command (ETG.1000.4 Table 12)
    std::uint16_t adp = 0, ado = 0;
    std::optional<std::uint32_t> addr;  // logical address (LRD/LWR/LRW) instead of Adp/Ado
    std::vector<std::uint8_t> data;     // Data, or DataLength zero bytes
    std::optional<std::uint16_t> cnt;   // expected working counter
    std::uint16_t retries = 0;
};

// A CoE InitCmd (ETG.2100 Mailbox/CoE/InitCmds/InitCmd): an SDO download (Ccs 1) or upload (Ccs 2).
struct EniCoeInitCmd {
    EniWhere where;
    EniTransitions transitions = 0;
    std::string comment;
    std::uint8_t ccs = 0;
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    bool complete_access = false;
    bool disabled = false;
    std::vector<std::uint8_t> data;
};

struct EniMailboxArea {
    std::uint16_t start = 0, length = 0;
};

struct EniMailbox {
    EniWhere where;
    EniMailboxArea send;  // master -> slave (SM0)
    EniMailboxArea recv;  // slave -> master (SM1)
    std::optional<EniMailboxArea> boot_send, boot_recv;
    std::uint16_t protocols = 0;  // device::mbx_proto bits
    std::vector<EniCoeInitCmd> coe_init_cmds;
};

// ProcessData/Sm<n>: a process data SyncManager as the configurator set it.
struct EniSyncManager {
    EniWhere where;
    unsigned number = 0;   // n of Sm<n>, 0..3 (ETG.2100 names Sm0..Sm3)
    bool outputs = false;  // Type: Outputs (master -> slave) or Inputs
    std::uint16_t start = 0, default_size = 0;
    std::uint8_t control = 0;
    bool enable = false;
    std::vector<std::uint16_t> pdos;  // the PDOs assigned to it
};

struct EniPdoEntry {
    EniWhere where;
    std::uint16_t index = 0;  // 0: a gap
    std::uint8_t subindex = 0;
    std::uint8_t bit_length = 0;
    std::string name;
    std::string data_type;  // ETG base type name (UINT, BOOL...), may be empty
};

struct EniPdo {
    EniWhere where;
    std::uint16_t index = 0;
    std::string name;
    std::optional<std::uint8_t> sm;  // attribute Sm
    bool fixed = false, mandatory = false;
    std::vector<EniPdoEntry> entries;
};

// PreviousPort: this slave's port 0 is cabled to port `port` of the slave with station address phys_addr.
struct EniPreviousPort {
    EniWhere where;
    bool selected = false;
    unsigned port = 0;  // A-D: ESC ports 0-3
    std::optional<std::uint16_t> phys_addr;
};

struct EniSlave {
    EniWhere where;  // of the Slave element
    std::string name;
    std::optional<std::uint16_t> phys_addr;      // station address the master gives it
    std::optional<std::uint16_t> auto_inc_addr;  // its position as the ENI has it (0, 0xFFFF, 0xFFFE...)
    std::string physics;                         // one letter per port: Y/H MII, K E-bus, ' ' none
    std::uint32_t vendor_id = 0, product_code = 0, revision = 0;
    std::optional<std::uint32_t> serial;
    std::optional<EniMailbox> mailbox;
    std::vector<EniSyncManager> sync_managers;
    std::vector<EniPdo> rx_pdos, tx_pdos;
    std::vector<EniInitCmd> init_cmds;
    std::vector<EniPreviousPort> previous_ports;
};

struct Eni {
    std::string file;  // the name used in messages
    std::string master_name;
    std::vector<EniInitCmd> master_init_cmds;
    std::vector<EniSlave> slaves;
};

// Reads an ENI file, or the text of one; throws EniError.
Eni read_eni_file(const std::string& path);
Eni parse_eni(const std::string& xml_text, const std::string& name = "<eni>");

// "FILE:LINE: PATH: what" for an element of eni.
std::string eni_message(const Eni& eni, const EniWhere& at, const std::string& what);

}  // namespace vecat::network
