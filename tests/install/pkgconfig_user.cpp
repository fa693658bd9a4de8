// Built by the install test with the flags of `pkg-config --cflags --libs vecat` only.
#include <cstdio>

#include "testing/virtual_segment.hpp"

int main() {
    vecat::testing::VirtualSegment vs({.drives = 1});
    const bool ok = vs.enable(0);
    std::printf("pkg-config user: drive %s\n", ok ? "enabled" : "NOT enabled");
    return ok ? 0 : 1;
}
