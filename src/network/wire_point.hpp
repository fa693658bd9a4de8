// Where a wire of a network file finds an output of a device of an ESI file or SII dump (build.cpp).
#pragma once

#include <string>
#include <vector>

#include "device/device_description.hpp"
#include "io/signal.hpp"
#include "io/terminals.hpp"

namespace vecat::network {

// A wire's output of a device of an ESI file or SII dump (docs/network-file.md): channel N, its N-th one-bit
// output PDO entry of the default mapping (the assigned RxPDOs in order, their entries packed, gaps count);
// 0xINDEX:SUB, that output PDO entry (1 to 32 bits). An entry of the default mapping has its place in the
// image; a device with a CoE dictionary shows the entry's object instead (make_app in build.cpp). objects:
// the dictionary of a device with a CoE mailbox, whose master may assign the RxPDOs the default leaves out:
// 0xINDEX:SUB may name an entry of those too, if the dictionary has its object; such a point has no place in
// the image (in_image false) and reads only its object. nullptr: a device without CoE, its default mapping
// only. Throws the line's NetworkFileError (at: "FILE:LINE: NAME: ") when the device has no such output.
io::ImagePoint wire_point(const device::DeviceDescription& d,
                          const std::vector<device::ObjectDescription>* objects, const std::string& target,
                          const io::Signal& s, const std::string& at);

}  // namespace vecat::network
