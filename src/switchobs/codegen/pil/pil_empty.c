/* An empty step with the signature of <prefix>_step, in its own translation unit so that the call is
 * not inlined: the loop through it is the harness's own cost, subtracted from the counted instructions. */
#include <stdint.h>

#include "pil_config.h"

int32_t pil_empty_step(pil_real *xhat, const pil_real *signals, const pil_real *params, pil_real dt);

int32_t pil_empty_step(pil_real *xhat, const pil_real *signals, const pil_real *params, pil_real dt)
{
    (void)xhat;
    (void)signals;
    (void)params;
    (void)dt;
    return 0;
}
