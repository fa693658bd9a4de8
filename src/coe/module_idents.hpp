// The configuration check of a modular device (ETG.5001.1 Modular Device Profile, device area): the master
// writes the modules it expects into the Configured Module Ident List 0xF030 in PREOP; PREOP -> SAFEOP is
// refused when they differ from the Detected Module Ident List 0xF050 (AL status code 0x0070, ETG.1000.6
// Table 11). A device without both objects, or a 0xF030 with 0 entries (nothing configured), passes.
#pragma once

#include "coe/object_dictionary.hpp"
#include "protocol/al_status.hpp"

namespace vecat::coe {

protocol::AlStatusCode check_module_idents(const ObjectDictionary& od);

}  // namespace vecat::coe
