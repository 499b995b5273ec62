/* occseg.h must compile warning-free as strict C99 (-std=c99 -Wall -Wextra -pedantic -Werror)
 * and be safe to include twice. */
#include <occseg/occseg.h>
#include <occseg/occseg.h>

int header_c99_probe(void);
int header_c99_probe(void) { return OCCSEG_VERSION_NUMBER == OCCSEG_VERSION_MAJOR * 10000 + OCCSEG_VERSION_MINOR * 100 + OCCSEG_VERSION_PATCH; }
