/* ctl_driver.c - host driver of the closed-loop controller (nnik_ctl.h): reads lines
 * "ref_x ref_y pos_x pos_y" (a line "r" resets the controller) and prints "duty_x duty_y sum" per tick:
 * sum is the controller's weights' checksum nnik_ctl_sum when it keeps one (the neural controllers;
 * a weak reference, so the others link without it and print 0). */
#include <stdio.h>
#include <stdint.h>

#include "nnik_ctl.h"

extern uint16_t nnik_ctl_sum __attribute__((weak));

int main(void)
{
    long rx, ry, px, py;
    char c;
    nnik_ctl_reset();
    for (;;) {
        if (scanf(" %c", &c) != 1)
            break;
        if (c == 'r') {
            nnik_ctl_reset();
            continue;
        }
        ungetc(c, stdin);
        if (scanf("%ld %ld %ld %ld", &rx, &ry, &px, &py) != 4)
            return 1;
        {
            int32_t ref[2] = {(int32_t)rx, (int32_t)ry}, pos[2] = {(int32_t)px, (int32_t)py};
            int16_t duty[2];
            nnik_ctl_tick(ref, pos, duty);
            printf("%d %d %u\n", duty[0], duty[1], &nnik_ctl_sum ? (unsigned)nnik_ctl_sum : 0u);
        }
    }
    return 0;
}
