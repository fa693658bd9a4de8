// Fuzz target: ESI import (esi::import_esi_text) and what vecat run --esi does with the result: completes
// it for emulation, builds the SII image and the dictionary, and starts a slave on it.
// Invariants: a file is either refused with an exception (what vecat reports and stops on) or gives a
// description whose SII image parses back with the same identity, and whose slave can be built. A modular
// device imported again with chosen modules (network file modules:; each slot another slot's module, or
// empty) gives one ModuleIdent per slot (at least one per entry: Slot elements repeat) or is refused with a
// ModuleError naming an entry of the list.
#include <cstdint>
#include <exception>
#include <memory>
#include <optional>
#include <string>

#include "coe/coe_application.hpp"
#include "esc/sii_image.hpp"
#include "esi/esi_reader.hpp"
#include "fuzz_support.hpp"
#include "protocol/objects.hpp"

using namespace vecat;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string xml(reinterpret_cast<const char*>(data), size);
    esi::ImportResult r;
    try {
        r = esi::import_esi_text(xml);
        esi::complete_for_emulation(r.desc);
    } catch (const std::exception&) {
        return 0;  // refused: vecat prints the reason and stops
    }
    auto& d = r.desc;
    if (!d.module_idents.empty()) {
        // Slot i takes the default module of the slot after it (the last one stays empty), by ModuleIdent.
        esi::DeviceSelector sel;
        sel.modules.emplace();
        const std::size_t n = d.module_idents.size();
        for (std::size_t i = 0; i < n; ++i)
            if (i + 1 < n)
                sel.modules->push_back(std::to_string(d.module_idents[i + 1]));
            else
                sel.modules->push_back(std::nullopt);
        try {
            // Every entry one slot; Slot elements the list does not reach add their default ones.
            const auto chosen = esi::import_esi_text(xml, sel);
            VECAT_FUZZ_CHECK(chosen.desc.module_idents.size() >= n);
            VECAT_FUZZ_CHECK(chosen.desc.module_idents.size() <= protocol::obj::modular_device::max_slots);
        } catch (const esi::ModuleError& e) {
            VECAT_FUZZ_CHECK(e.entry && *e.entry < n);
        } catch (const std::exception&) {
            // refused for what else the chosen modules bring (an SII that does not fit)
        }
    }
    auto img = esc::build_sii_image(d);
    VECAT_FUZZ_CHECK(img.size() == d.eeprom_size_bytes);
    const auto info = protocol::parse_sii(ConstBytes(img.data(), img.size()));
    VECAT_FUZZ_CHECK(info.checksum_ok);
    VECAT_FUZZ_CHECK(info.identity.vendor_id == d.identity.vendor_id);
    VECAT_FUZZ_CHECK(info.identity.product_code == d.identity.product_code);
    // The model from the image checked above (DeviceModel::of would build it a second time).
    const esc::DeviceModel model{
        std::make_shared<const device::DeviceDescription>(d),
        std::make_shared<const std::vector<std::uint8_t>>(std::move(img)),
        std::make_shared<const std::vector<device::ObjectDescription>>(device::dictionary_objects(d))};
    auto seg = coe::make_coe_segment(model, 1);
    std::uint64_t now = 1'000'000'000;
    fuzz::bring_to_preop(*seg, d, now);  // may be refused (odd mailboxes); must not crash
    return 0;
}
