// Private network namespaces and veth pairs for tests and the demo. A namespace made by
// enter_private_netns() belongs to this process alone and disappears with it, with its interfaces.
#pragma once

#include <string>

namespace vecat::net {

// Moves the calling process (call it before starting threads) into a new network namespace. As root that is
// all; as an ordinary user the process first enters a new user namespace (unprivileged user namespaces, no
// setuid helper) in which it is root with the capabilities that a veth pair and raw sockets need, for its
// own namespaces only. Returns false with a reason, and how to allow it, when that is not permitted.
bool enter_private_netns(std::string* why = nullptr);

// True when the process runs inside a user namespace that enter_private_netns made.
bool in_private_user_namespace();

// What stops unprivileged user namespaces on this machine, and how to allow them ("" when nothing known).
std::string user_namespace_hint();

// Brings the loopback interface of the current namespace up.
bool loopback_up(std::string* why = nullptr);

// Creates a veth pair inside the current namespace, brings both ends up and waits (up to 3 s) until both
// have their carrier, so that the first frames are not dropped. Returns false with a reason.
bool create_veth_pair(const std::string& a, const std::string& b, std::string* why = nullptr);

// True when the interface carries an IPv4 or IPv6 address (link-local IPv6 aside: every interface that is
// up has one), is the IPv4 or IPv6 default route's interface, or is a port of a bridge or bond.
bool interface_in_use(const std::string& ifname, std::string* why = nullptr);

}  // namespace vecat::net
