// Locating the shared data files (common/<kind>/<name>.json): now part of the config layer
// (config.hpp, resolve_data_file); this header stays for the code that includes it.
#pragma once

#include "omniloc/config.hpp"
