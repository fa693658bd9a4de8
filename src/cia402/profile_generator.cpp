#include "cia402/profile_generator.hpp"
