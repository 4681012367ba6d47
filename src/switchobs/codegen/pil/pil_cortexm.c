/* Bare-metal start-up of the harness on the MPS2 boards that qemu models (mps2-an386: Cortex-M4,
 * mps2-an500: Cortex-M7): vector table, .data/.bss set-up, FPU enable, ARM semihosting for output and
 * exit, and CMSDK APB timer 0 as the counter.  Under `qemu-system-arm -icount shift=0` every instruction
 * advances the virtual clock by 1 ns and the 25 MHz timer by 1/40 of a tick; pil_calibrate measures that
 * ratio on a loop of known length, so the count does not rely on the board's clock. */
#include <stdint.h>

void pil_write(const char *text);
uint32_t pil_ticks(void);
uint32_t pil_calibrate(void);
int pil_main(void);
void pil_reset(void);
void pil_fault(void);

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;

#define PIL_TIMER0 ((volatile uint32_t *)0x40000000u)  /* CTRL, VALUE, RELOAD */
#define PIL_CPACR (*(volatile uint32_t *)0xE000ED88u)
#define PIL_CALIBRATION_LOOPS 1048576u  /* 2 instructions each */

__attribute__((section(".vectors"), used))
static void (*const pil_vectors[16])(void) = {
    (void (*)(void))(uintptr_t)&_estack, pil_reset, pil_fault, pil_fault, pil_fault, pil_fault, pil_fault,
    0, 0, 0, 0, pil_fault, pil_fault, 0, pil_fault, pil_fault,
};

static int32_t pil_semihost(int32_t op, const void *arg)
{
    register int32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void pil_write(const char *text) { (void)pil_semihost(0x04, text); }  /* SYS_WRITE0 */

uint32_t pil_ticks(void) { return 0u - PIL_TIMER0[1]; }  /* counts down: negated, so that later - earlier */

uint32_t pil_calibrate(void)
{
    uint32_t t0 = pil_ticks(), t1;
    __asm__ volatile("mov r2, %0\n1:\n subs r2, r2, #1\n bne 1b" : : "r"(PIL_CALIBRATION_LOOPS) : "r2", "cc");
    t1 = pil_ticks();
    return t1 - t0;
}

static void pil_exit(uint32_t reason)
{
    (void)pil_semihost(0x18, (const void *)(uintptr_t)reason);  /* SYS_EXIT */
    for (;;) {
    }
}

void pil_fault(void)
{
    pil_write("FAULT\n");
    pil_exit(0x20023u);  /* ADP_Stopped_RunTimeErrorUnknown: qemu exits 1 */
}

void pil_reset(void)
{
    uint32_t *src = &_sidata, *dst;
    for (dst = &_sdata; dst < &_edata; ++dst) *dst = *src++;
    for (dst = &_sbss; dst < &_ebss; ++dst) *dst = 0u;
#if defined(__ARM_FP)
    PIL_CPACR |= 0xFu << 20;  /* CP10, CP11: full access to the FPU */
    __asm__ volatile("dsb\n isb" : : : "memory");
#endif
    PIL_TIMER0[2] = 0xFFFFFFFFu;
    PIL_TIMER0[1] = 0xFFFFFFFFu;
    PIL_TIMER0[0] = 1u;
    (void)pil_main();
    pil_exit(0x20026u);  /* ADP_Stopped_ApplicationExit: qemu exits 0 */
}
