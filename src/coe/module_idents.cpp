#include "coe/module_idents.hpp"

#include "protocol/objects.hpp"

namespace vecat::coe {

protocol::AlStatusCode check_module_idents(const ObjectDictionary& od) {
    namespace md = protocol::obj::modular_device;
    const Entry* configured_count = od.find(md::configured_module_ident_list, 0);
    const Entry* detected_count = od.find(md::detected_module_ident_list, 0);
    if (!configured_count || !detected_count) return protocol::AlStatusCode::NoError;
    const auto n = configured_count->get<std::uint8_t>();
    if (n == 0) return protocol::AlStatusCode::NoError;
    if (n != detected_count->get<std::uint8_t>()) return protocol::AlStatusCode::ModuleIdentListMismatch;
    for (unsigned sub = 1; sub <= n; ++sub) {
        const Entry* c = od.find(md::configured_module_ident_list, static_cast<std::uint8_t>(sub));
        const Entry* d = od.find(md::detected_module_ident_list, static_cast<std::uint8_t>(sub));
        if (!c || !d || c->get<std::uint32_t>() != d->get<std::uint32_t>())
            return protocol::AlStatusCode::ModuleIdentListMismatch;
    }
    return protocol::AlStatusCode::NoError;
}

}  // namespace vecat::coe
