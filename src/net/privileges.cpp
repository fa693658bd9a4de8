#include "net/privileges.hpp"

#include <sys/capability.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cstring>

namespace vecat::net {

bool drop_all_capabilities(std::string* why) {
    // The bounding set first: dropping from it needs CAP_SETPCAP, which the next step removes.
    for (int cap = 0; cap <= CAP_LAST_CAP; ++cap)
        ::prctl(PR_CAPBSET_DROP, cap, 0, 0, 0);  // EPERM without CAP_SETPCAP: the process sets still go
    ::prctl(PR_CAP_AMBIENT, PR_CAP_AMBIENT_CLEAR_ALL, 0, 0, 0);
    cap_t none = cap_init();  // all three sets empty
    if (!none) {
        if (why) *why = std::string("cap_init: ") + std::strerror(errno);
        return false;
    }
    const int rc = cap_set_proc(none);
    const int err = errno;
    cap_free(none);
    if (rc != 0) {
        if (why) *why = std::string("cap_set_proc: ") + std::strerror(err);
        return false;
    }
    if (::prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) {
        if (why) *why = std::string("PR_SET_NO_NEW_PRIVS: ") + std::strerror(errno);
        return false;
    }
    return true;
}

}  // namespace vecat::net
