#include "cia402/drive.hpp"
