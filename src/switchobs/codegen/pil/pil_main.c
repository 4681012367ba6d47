/* Processor-in-the-loop harness of switchobs (switchobs.codegen.run_pil): runs <prefix>_step over a
 * record, one call per row, and prints every status and state as the bytes of the real type.
 *
 * The same file is built for the host (PIL_HOST: stdio) and for the bare-metal Cortex-M target
 * (pil_cortexm.c: semihosting output, a CMSDK timer counting under qemu's -icount).  A refused row
 * leaves the state as it was and the next row goes on from it, as an ECU task would.
 *
 * Output lines: "CAL <ticks>" (the calibration loop), "RUN <ticks>" (the record through _step),
 * "BASE <ticks>" (the same loop through an empty function of the same signature), then one line per
 * row: "R <status> <hex bytes of the state after the row>". */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "pil_config.h"

void pil_write(const char *text);
uint32_t pil_ticks(void);
uint32_t pil_calibrate(void);
int32_t pil_empty_step(pil_real *xhat, const pil_real *signals, const pil_real *params, pil_real dt);
int pil_main(void);

static pil_real states[PIL_ROWS][PIL_NX];
static int32_t statuses[PIL_ROWS];

typedef int32_t (*pil_stepper)(pil_real *, const pil_real *, const pil_real *, pil_real);

/* The loop the instructions are counted over: one call per row, the state copied out after it. */
static uint32_t pil_loop(pil_stepper step)
{
    pil_real x[PIL_NX];
    uint32_t t0, t1;
    size_t k;
    memcpy(x, pil_x0, sizeof x);
    t0 = pil_ticks();
    for (k = 0u; k < (size_t)PIL_ROWS; ++k) {
        statuses[k] = step(x, &pil_signals[k * (size_t)PIL_NS], NULL, pil_dt[k]);
        memcpy(states[k], x, sizeof x);
    }
    t1 = pil_ticks();
    return t1 - t0;  /* the timer counts down on the target, up on the host (0) */
}

static char line[32 + 3 * PIL_NX * sizeof(pil_real)];

static size_t pil_hex(char *out, const unsigned char *bytes, size_t n)
{
    static const char digits[] = "0123456789abcdef";
    size_t i;
    for (i = 0u; i < n; ++i) {
        out[2u * i] = digits[bytes[i] >> 4];
        out[2u * i + 1u] = digits[bytes[i] & 15u];
    }
    return 2u * n;
}

static void pil_number(const char *tag, uint32_t value)
{
    size_t n = strlen(tag);
    unsigned char be[4];
    memcpy(line, tag, n);
    line[n++] = ' ';
    be[0] = (unsigned char)(value >> 24); be[1] = (unsigned char)(value >> 16);
    be[2] = (unsigned char)(value >> 8); be[3] = (unsigned char)value;
    n += pil_hex(line + n, be, 4u);
    line[n++] = '\n';
    line[n] = '\0';
    pil_write(line);
}

int pil_main(void)
{
    uint32_t cal, run, base;
    size_t k, n;
    cal = pil_calibrate();
    base = pil_loop(pil_empty_step);
    run = pil_loop(PIL_STEP);
    pil_number("CAL", cal);
    pil_number("RUN", run);
    pil_number("BASE", base);
    for (k = 0u; k < (size_t)PIL_ROWS; ++k) {
        unsigned char st[4];
        uint32_t s = (uint32_t)statuses[k];
        st[0] = (unsigned char)(s >> 24); st[1] = (unsigned char)(s >> 16);
        st[2] = (unsigned char)(s >> 8); st[3] = (unsigned char)s;
        line[0] = 'R';
        line[1] = ' ';
        n = 2u + pil_hex(line + 2, st, 4u);
        line[n++] = ' ';
        n += pil_hex(line + n, (const unsigned char *)states[k], sizeof states[k]);
        line[n++] = '\n';
        line[n] = '\0';
        pil_write(line);
    }
    pil_write("END\n");
    return 0;
}
