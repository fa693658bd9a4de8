#include "cia402/state_machine.hpp"
