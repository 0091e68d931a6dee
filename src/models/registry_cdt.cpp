// The presets of COHDEM_ROLLING_LAWS with rolling = "cdt" (CdtRolling), compiled in a file of
// their own (registry_laws.hpp says why).
#include "models/registry_instance.hpp"

COHDEM_INSTANTIATE_ROLLING(CdtRolling)
