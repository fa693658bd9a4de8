// Fuzz target: the dictionary file reader (network::parse_dictionary: YAML, objects, entries, hex values).
// Input: the text of a file.
// Invariants: the text is accepted or refused with a DictionaryFileError that names the file ("NAME:LINE:
// ..." or "NAME: ..."); nothing else is thrown. An accepted dictionary has its objects sorted by index, each
// with its entries sorted by subindex and a max subindex at least its last entry's, every value within its
// entry's bits; written again and read back, it gives the same text (the writer and the reader agree).
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "network/dictionary_file.hpp"

using namespace vecat;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    network::DeviceDictionary d;
    try {
        d = network::parse_dictionary(text, "fuzz.yaml");
    } catch (const network::DictionaryFileError& e) {
        VECAT_FUZZ_CHECK(std::string(e.what()).rfind("fuzz.yaml", 0) == 0);
        return 0;
    }
    VECAT_FUZZ_CHECK(!d.objects.empty());
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
        const auto& o = d.objects[i];
        if (i > 0) VECAT_FUZZ_CHECK(d.objects[i - 1].index < o.index);
        VECAT_FUZZ_CHECK(!o.entries.empty());
        for (std::size_t k = 1; k < o.entries.size(); ++k)
            VECAT_FUZZ_CHECK(o.entries[k - 1].subindex < o.entries[k].subindex);
        VECAT_FUZZ_CHECK(o.max_subindex() >= o.entries.back().subindex);
    }
    for (const auto& [at, bytes] : d.values) {
        const device::ObjectDescription* o = nullptr;
        for (const auto& x : d.objects)
            if (x.index == at.first) o = &x;
        VECAT_FUZZ_CHECK(o != nullptr);
        const auto* e = o->entry(at.second);
        VECAT_FUZZ_CHECK(e != nullptr);
        VECAT_FUZZ_CHECK(bytes.size() <= std::max<std::size_t>(1, (e->bit_length + 7u) / 8u));
    }
    const std::string once = network::write_dictionary(d);
    network::DeviceDictionary back;
    try {
        back = network::parse_dictionary(once, "fuzz.yaml");
    } catch (const network::DictionaryFileError& e) {
        std::fprintf(stderr, "the written dictionary is refused: %s\n", e.what());
        VECAT_FUZZ_CHECK(false);
    }
    VECAT_FUZZ_CHECK(network::write_dictionary(back) == once);
    return 0;
}
