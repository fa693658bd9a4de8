#include "cia402/homing.hpp"
