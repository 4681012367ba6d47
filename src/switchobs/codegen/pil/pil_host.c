/* Host side of the harness: stdio output, no instruction counting. */
#include <stdint.h>
#include <stdio.h>

void pil_write(const char *text);
uint32_t pil_ticks(void);
uint32_t pil_calibrate(void);
int pil_main(void);

void pil_write(const char *text) { (void)fputs(text, stdout); }
uint32_t pil_ticks(void) { return 0u; }
uint32_t pil_calibrate(void) { return 0u; }

int main(void) { return pil_main(); }
