/* A shared library that is not a twinray plugin (no twinray_plugin_entry): loading must fail cleanly. */
#include "twinray_plugin.h"

TWINRAY_PLUGIN_EXPORT int not_a_plugin(void);
TWINRAY_PLUGIN_EXPORT int not_a_plugin(void) { return 42; }
