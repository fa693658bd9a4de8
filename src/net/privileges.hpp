// Least privilege for vecat run: once the raw socket is open the process needs no capability at all (an
// open AF_PACKET socket sends and receives without one; the kernel checks CAP_NET_RAW only when it is
// created). drop_all_capabilities() clears the effective, permitted, inheritable and ambient sets and the
// bounding set, and sets no_new_privs, so nothing the process does later can regain them.
#pragma once

#include <string>

namespace vecat::net {

// False with a reason if the permitted set could not be cleared (the bounding set is cleared when
// CAP_SETPCAP allows it; without it, e.g. under file capabilities, only the process sets are).
bool drop_all_capabilities(std::string* why = nullptr);

}  // namespace vecat::net
