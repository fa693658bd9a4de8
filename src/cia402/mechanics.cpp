#include "cia402/mechanics.hpp"
