#include "coe/pdo_mapping.hpp"

#include <algorithm>
#include <cstring>

#include "common/bits.hpp"
#include "protocol/registers.hpp"

namespace vecat::coe {
namespace {

constexpr unsigned kEscRamEnd = 0x3000;  // process RAM 0x1000..0x2FFF (8 KiB)

unsigned max_sm_bytes(const device::DeviceDescription& desc, device::SmType type) {
    const auto* sm = desc.sm_of_type(type);
    if (!sm) return 0;
    // Below the process RAM a SyncManager lies on the digital output register 0x0F00-0x0F03, one byte
    // without buffers each (ESC datasheet section I 8.5).
    const bool digital_outputs = sm->start < protocol::kRegisterSpaceSize;
    unsigned next = digital_outputs
                        ? protocol::addr(protocol::Reg::DigitalOutputData) + protocol::kDigitalOutputSize
                        : kEscRamEnd;
    for (const auto& s : desc.sync_managers)
        if (s.start > sm->start && s.start < next) next = s.start;
    if (next <= sm->start) return 0;
    // A buffered SyncManager occupies three buffers of its length.
    return digital_outputs ? std::min(next - sm->start, 1u) : (next - sm->start) / 3;
}

std::uint32_t u32_of(ConstBytes b) {
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < std::min<std::size_t>(4, b.size()); ++i)
        v |= static_cast<std::uint32_t>(b[i]) << (8 * i);
    return v;
}

}  // namespace

ProcessDataMap::ProcessDataMap(ObjectDictionary& od, const device::DeviceDescription& desc)
    : od_(od), remapping_(desc.pdo_remapping) {
    if (auto sm = desc.sm_index_of_type(device::SmType::Outputs))
        rx_ = {static_cast<std::uint16_t>(0x1C10 + *sm), 0x1600, true,
               max_sm_bytes(desc, device::SmType::Outputs)};
    if (auto sm = desc.sm_index_of_type(device::SmType::Inputs))
        tx_ = {static_cast<std::uint16_t>(0x1C10 + *sm), 0x1A00, false,
               max_sm_bytes(desc, device::SmType::Inputs)};
    max_out_ = rx_.max_bytes;
    max_in_ = tx_.max_bytes;
    if (rx_.assign_index) install(rx_);
    if (tx_.assign_index) install(tx_);
    rebuild();
}

SdoAbort ProcessDataMap::check_mapping_entry(const Direction& d, std::uint32_t value) const {
    const auto m = MappingValue::decode(value);
    if (m.bits == 0) return SdoAbort::NotMappable;
    if (m.is_gap()) return SdoAbort::None;
    const Entry* e = const_cast<ObjectDictionary&>(od_).find(m.index, m.subindex);
    if (!e) return SdoAbort::NotMappable;
    if (d.rx ? !e->rx_mappable() : !e->tx_mappable()) return SdoAbort::NotMappable;
    if (e->bit_length() != m.bits) return SdoAbort::NotMappable;
    return SdoAbort::None;
}

bool ProcessDataMap::pdo_bits(const Direction& d, std::uint16_t pdo, int count, unsigned& bits) const {
    const Object* o = od_.find(pdo);
    if (!o || pdo < d.first_pdo || pdo > d.first_pdo + 0x1FF) return false;
    const Entry* s0 = o->entry(0);
    const int n = count >= 0 ? count : static_cast<int>(s0 ? s0->as_uint64() : 0);
    bits = 0;
    for (int i = 1; i <= n; ++i) {
        const Entry* e = o->entry(static_cast<std::uint8_t>(i));
        if (!e) return false;
        const std::uint32_t v = e->get<std::uint32_t>();
        if (check_mapping_entry(d, v) != SdoAbort::None) return false;
        bits += MappingValue::decode(v).bits;
    }
    return true;
}

// Total bits of the assigned PDOs, as if PDO changed_pdo had changed_count entries and the assignment
// had assign_count PDOs (-1: current values).
bool ProcessDataMap::assigned_bits(const Direction& d, std::uint16_t changed_pdo, int changed_count,
                                   int assign_count, unsigned& bits) const {
    const Object* a = od_.find(d.assign_index);
    if (!a) return false;
    const int n = assign_count >= 0 ? assign_count : static_cast<int>(a->entry(0)->as_uint64());
    bits = 0;
    for (int i = 1; i <= n; ++i) {
        const Entry* e = a->entry(static_cast<std::uint8_t>(i));
        if (!e) return false;
        const auto pdo = e->get<std::uint16_t>();
        unsigned b = 0;
        if (!pdo_bits(d, pdo, pdo == changed_pdo ? changed_count : -1, b)) return false;
        bits += b;
    }
    return true;
}

// Whether pdo is one of the PDOs the assignment of d now lists (0x1C1x:1..n, n = 0x1C1x:0).
bool ProcessDataMap::is_assigned(const Direction& d, std::uint16_t pdo) const {
    const Object* a = od_.find(d.assign_index);
    if (!a) return false;
    const auto n = a->entry(0)->as_uint64();
    for (std::uint64_t i = 1; i <= n; ++i)
        if (const Entry* e = a->entry(static_cast<std::uint8_t>(i)); e && e->get<std::uint16_t>() == pdo)
            return true;
    return false;
}

void ProcessDataMap::install(const Direction& d) {
    Object* assign = od_.find(d.assign_index);
    if (!assign) return;
    auto on_change = [this](Entry&) { rebuild(); };
    for (auto& e : assign->entries()) {
        e.hooks().after_download = on_change;
        if (e.subindex() == 0) {
            e.hooks().on_download = [this, d, assign](const Entry&, ConstBytes v) {
                const int n = v.empty() ? 0 : v[0];
                for (int i = 1; i <= n; ++i) {
                    const Entry* s = assign->entry(static_cast<std::uint8_t>(i));
                    if (!s) return SdoAbort::ValueTooHigh;
                    const auto pdo = s->get<std::uint16_t>();
                    unsigned b = 0;
                    if (!pdo_bits(d, pdo, -1, b)) return SdoAbort::ParameterIncompatible;
                    for (int j = 1; j < i; ++j)
                        if (assign->entry(static_cast<std::uint8_t>(j))->get<std::uint16_t>() == pdo)
                            return SdoAbort::ParameterIncompatible;  // the same PDO twice
                }
                unsigned bits = 0;
                if (!assigned_bits(d, 0, -1, n, bits)) return SdoAbort::ParameterIncompatible;
                if (bits > d.max_bytes * 8) return SdoAbort::PdoLengthExceeded;
                return SdoAbort::None;
            };
        } else {
            e.hooks().on_download = [this, d, assign](const Entry&, ConstBytes v) {
                if (assign->entry(0)->as_uint64() != 0) return SdoAbort::Subindex0NotZero;
                const auto pdo = static_cast<std::uint16_t>(v.size() >= 2 ? v[0] | (v[1] << 8) : 0);
                if (pdo == 0) return SdoAbort::None;  // clearing an unused slot
                const Object* o = od_.find(pdo);
                if (!o || pdo < d.first_pdo || pdo > d.first_pdo + 0x1FF) return SdoAbort::ValueRange;
                return SdoAbort::None;
            };
        }
    }
    for (auto& o : od_.objects()) {
        if (o.index() < d.first_pdo || o.index() > d.first_pdo + 0x1FF) continue;
        Object* po = &o;
        const std::uint16_t pdo = o.index();
        for (auto& e : o.entries()) {
            e.hooks().after_download = on_change;
            if (e.subindex() == 0) {
                e.hooks().on_download = [this, d, po, pdo](const Entry&, ConstBytes v) {
                    const int n = v.empty() ? 0 : v[0];
                    for (int i = 1; i <= n; ++i) {
                        const Entry* s = po->entry(static_cast<std::uint8_t>(i));
                        if (!s) return SdoAbort::ValueTooHigh;
                        if (auto a = check_mapping_entry(d, s->get<std::uint32_t>()); a != SdoAbort::None)
                            return a;
                    }
                    unsigned own = 0;
                    if (!pdo_bits(d, pdo, n, own)) return SdoAbort::NotMappable;
                    if (own > d.max_bytes * 8) return SdoAbort::PdoLengthExceeded;
                    unsigned bits = 0;
                    if (assigned_bits(d, pdo, n, -1, bits) && bits > d.max_bytes * 8)
                        return SdoAbort::PdoLengthExceeded;
                    return SdoAbort::None;
                };
            } else {
                e.hooks().on_download = [this, d, po, pdo](const Entry&, ConstBytes v) {
                    if (remapping_ == device::PdoRemapping::Subindex0Zero ? po->entry(0)->as_uint64() != 0
                                                                          : is_assigned(d, pdo))
                        return SdoAbort::Subindex0NotZero;
                    const std::uint32_t value = u32_of(v);
                    if (value == 0) return SdoAbort::None;  // clearing an unused entry
                    return check_mapping_entry(d, value);
                };
            }
        }
    }
}

bool ProcessDataMap::build(const Direction& d, std::vector<MappedField>& fields, unsigned& bytes) {
    fields.clear();
    bytes = 0;
    const Object* a = od_.find(d.assign_index);
    if (!a) return true;
    std::uint32_t bit = 0;
    bool ok = true;
    const auto n = a->entry(0)->as_uint64();
    for (std::uint64_t i = 1; i <= n; ++i) {
        const Entry* ae = a->entry(static_cast<std::uint8_t>(i));
        if (!ae) return false;
        const auto pdo = ae->get<std::uint16_t>();
        Object* po = od_.find(pdo);
        if (!po || pdo < d.first_pdo || pdo > d.first_pdo + 0x1FF) {
            ok = false;
            continue;
        }
        const auto m = po->entry(0)->as_uint64();
        for (std::uint64_t k = 1; k <= m; ++k) {
            Entry* me = po->entry(static_cast<std::uint8_t>(k));
            if (!me) {
                ok = false;
                break;
            }
            const std::uint32_t v = me->get<std::uint32_t>();
            if (check_mapping_entry(d, v) != SdoAbort::None) {
                ok = false;
                continue;
            }
            const auto mv = MappingValue::decode(v);
            fields.push_back({mv.is_gap() ? nullptr : od_.find(mv.index, mv.subindex), bit, mv.bits});
            bit += mv.bits;
        }
    }
    bytes = (bit + 7) / 8;
    if (bytes > d.max_bytes) ok = false;
    return ok;
}

void ProcessDataMap::rebuild() {
    ++mapping_changes_;
    if (rx_.assign_index) out_valid_ = build(rx_, out_, out_bytes_);
    if (tx_.assign_index) in_valid_ = build(tx_, in_, in_bytes_);
    out_plan_ = make_plan(out_);
    in_plan_ = make_plan(in_);
}

ProcessDataMap::Plan ProcessDataMap::make_plan(const std::vector<MappedField>& fields) {
    Plan p;
    p.fields.reserve(fields.size());
    for (unsigned k = 0; k < 4; ++k) {
        const unsigned n = 1u << k;
        for (const auto& f : fields) {
            if (!f.entry) continue;  // a gap: nothing to copy
            const unsigned size = f.bits / 8u;
            if (f.bit_offset % 8 != 0 || f.bits % 8 != 0 ||
                (size != 1 && size != 2 && size != 4 && size != 8) || f.entry->storage().size() < size)
                return Plan{};
            if (size == n) p.fields.push_back({f.entry->storage().data(), f.bit_offset / 8u});
        }
        p.end[k + 1] = static_cast<std::uint32_t>(p.fields.size());
    }
    p.ok = true;
    return p;
}

template <bool ToImage>
bool ProcessDataMap::run_plan(const Plan& p, ImagePtr<ToImage> image) {
    bool changed = false;
    const auto group = [&]<std::size_t N>(unsigned k) {
        for (std::uint32_t i = p.end[k]; i < p.end[k + 1]; ++i) {
            const FastField& f = p.fields[i];
            if constexpr (ToImage) {
                std::memcpy(image + f.byte, f.value, N);  // fixed size: one load and one store
            } else {
                changed = changed || std::memcmp(f.value, image + f.byte, N) != 0;
                std::memcpy(f.value, image + f.byte, N);
            }
        }
    };
    group.template operator()<1>(0);
    group.template operator()<2>(1);
    group.template operator()<4>(2);
    group.template operator()<8>(3);
    return changed;
}

protocol::AlStatusCode ProcessDataMap::validate() const {
    if (!out_valid_) return protocol::AlStatusCode::InvalidOutputMapping;
    if (!in_valid_) return protocol::AlStatusCode::InvalidInputMapping;
    return protocol::AlStatusCode::NoError;
}

void ProcessDataMap::copy_outputs(ConstBytes image) {
    if (out_plan_.ok && image.size() >= out_bytes_) {
        if (run_plan<false>(out_plan_, image.data())) ++outputs_changed_;
        return;
    }
    ++outputs_changed_;
    for (const auto& f : out_) {
        if (!f.entry || f.bit_offset + f.bits > image.size() * 8) continue;
        copy_bits(f.entry->storage().data(), 0, image.data(), f.bit_offset, f.bits);
    }
}

void ProcessDataMap::copy_inputs(Bytes image) const {
    if (in_plan_.ok && image.size() >= in_bytes_) {
        run_plan<true>(in_plan_, image.data());
        return;
    }
    for (const auto& f : in_) {
        if (f.bit_offset + f.bits > image.size() * 8) continue;
        if (!f.entry) continue;  // gaps keep whatever the image holds (zero)
        copy_bits(image.data(), f.bit_offset, f.entry->value().data(), 0, f.bits);
    }
}

bool ProcessDataMap::is_rx_mapped(const Entry& e) const {
    for (const auto& f : out_)
        if (f.entry == &e) return true;
    return false;
}

}  // namespace vecat::coe
