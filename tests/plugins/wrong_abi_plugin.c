/* A plugin that claims a future ABI version: twinray must refuse to load it (tests/test_plugin_backend.cpp). */
#include "twinray_plugin.h"

#include <stddef.h>

static const twinray_plugin_v1 future_table = {
    TWINRAY_PLUGIN_ABI_VERSION + 1u, "future", 0u, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL,
};

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &future_table; }
