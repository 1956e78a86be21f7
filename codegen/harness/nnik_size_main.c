/*
 * The smallest program that calls the model, to measure the model's own flash and RAM from the
 * linker map: everything the link adds for NNIK_IK (its code, its tables, its data and every
 * runtime routine it pulls in, such as __mulint or __mulsi3) is the model's, even if a larger
 * program would pull the same routine in for itself. Built twice: with NNIK_CALL=1, and with
 * NNIK_CALL=0 (no model) to learn which runtime pieces the startup code brings on its own.
 *
 * Compiled with -DNNIK_IK=<NAME>_ik -DNNIK_N_IN=.. -DNNIK_N_OUT=.. -DNNIK_CALL=0|1
 */
#ifdef __SDCC_pic16
#pragma stack 0x500 0xff /* as in the harness; the stack is not counted */
#endif
#include <stdint.h>

volatile int8_t nnik_size_sink; /* in both builds: the startup code that clears it is not the model's */
#if NNIK_CALL
int8_t NNIK_IK(const int32_t in_um[NNIK_N_IN], int32_t out[NNIK_N_OUT]);
#endif

#ifdef __SDCC
void main(void)
#else
int main(void)
#endif
{
#if NNIK_CALL
    int32_t in_um[NNIK_N_IN];
    int32_t out[NNIK_N_OUT];
    uint8_t i;

    for (i = 0; i < NNIK_N_IN; i++)
        in_um[i] = 0;
    nnik_size_sink = NNIK_IK(in_um, out);
    nnik_size_sink = (int8_t)out[0];
#endif
    for (;;)
        ;
}
