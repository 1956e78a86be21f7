/*
 * Core special function registers (and EEPROM pointer glue) of the PIC18F452
 * for SDCC's pic16 port.
 *
 * Debian's sdcc source package strips the (non-free) device headers and the
 * libdev18f452 library that normally define these symbols.  The code the
 * compiler emits and the pic16 runtime (libsdcc, crt0i) refer to the SFRs by
 * name (WREG, PRODL, FSR0L, POSTINC1, TBLPTRL, ...), so this file provides the
 * definitions.  Addresses: PIC18FXX2 datasheet (DS39564), table 4-1,
 * "Special function register map".  Compile with
 *     sdcc -mpic16 -p18f452 --use-non-free -c pic18f452_sfr.c
 * and link the object with the program.
 */

/* ---- stack / program counter ---- */
__sfr __at (0xFFF) TOSU;
__sfr __at (0xFFE) TOSH;
__sfr __at (0xFFD) TOSL;
__sfr __at (0xFFC) STKPTR;
__sfr __at (0xFFB) PCLATU;
__sfr __at (0xFFA) PCLATH;
__sfr __at (0xFF9) PCL;

/* ---- table read/write ---- */
__sfr __at (0xFF8) TBLPTRU;
__sfr __at (0xFF7) TBLPTRH;
__sfr __at (0xFF6) TBLPTRL;
__sfr __at (0xFF5) TABLAT;

/* ---- multiplier product ---- */
__sfr __at (0xFF4) PRODH;
__sfr __at (0xFF3) PRODL;

/* ---- interrupts ---- */
__sfr __at (0xFF2) INTCON;
__sfr __at (0xFF1) INTCON2;
__sfr __at (0xFF0) INTCON3;

/* ---- indirect addressing 0 ---- */
__sfr __at (0xFEF) INDF0;
__sfr __at (0xFEE) POSTINC0;
__sfr __at (0xFED) POSTDEC0;
__sfr __at (0xFEC) PREINC0;
__sfr __at (0xFEB) PLUSW0;
__sfr __at (0xFEA) FSR0H;
__sfr __at (0xFE9) FSR0L;

__sfr __at (0xFE8) WREG;

/* ---- indirect addressing 1 (SDCC's software stack pointer) ---- */
__sfr __at (0xFE7) INDF1;
__sfr __at (0xFE6) POSTINC1;
__sfr __at (0xFE5) POSTDEC1;
__sfr __at (0xFE4) PREINC1;
__sfr __at (0xFE3) PLUSW1;
__sfr __at (0xFE2) FSR1H;
__sfr __at (0xFE1) FSR1L;

__sfr __at (0xFE0) BSR;

/* ---- indirect addressing 2 (SDCC's frame pointer) ---- */
__sfr __at (0xFDF) INDF2;
__sfr __at (0xFDE) POSTINC2;
__sfr __at (0xFDD) POSTDEC2;
__sfr __at (0xFDC) PREINC2;
__sfr __at (0xFDB) PLUSW2;
__sfr __at (0xFDA) FSR2H;
__sfr __at (0xFD9) FSR2L;

__sfr __at (0xFD8) STATUS;

/* ---- timers / system ---- */
__sfr __at (0xFD7) TMR0H;
__sfr __at (0xFD6) TMR0L;
__sfr __at (0xFD5) T0CON;
__sfr __at (0xFD3) OSCCON;
__sfr __at (0xFD2) LVDCON;
__sfr __at (0xFD1) WDTCON;
__sfr __at (0xFD0) RCON;
__sfr __at (0xFCF) TMR1H;
__sfr __at (0xFCE) TMR1L;
__sfr __at (0xFCD) T1CON;

/* ---- data EEPROM ---- */
__sfr __at (0xFA9) EEADR;
__sfr __at (0xFA8) EEDATA;
__sfr __at (0xFA7) EECON2;
__sfr __at (0xFA6) EECON1;

/* ---- ports ---- */
__sfr __at (0xF96) TRISE;
__sfr __at (0xF95) TRISD;
__sfr __at (0xF94) TRISC;
__sfr __at (0xF93) TRISB;
__sfr __at (0xF92) TRISA;
__sfr __at (0xF8D) LATE;
__sfr __at (0xF8C) LATD;
__sfr __at (0xF8B) LATC;
__sfr __at (0xF8A) LATB;
__sfr __at (0xF89) LATA;
__sfr __at (0xF84) PORTE;
__sfr __at (0xF83) PORTD;
__sfr __at (0xF82) PORTC;
__sfr __at (0xF81) PORTB;
__sfr __at (0xF80) PORTA;

/*
 * Device glue normally in libdev18f452: the generic-pointer helpers of libsdcc
 * jump to __eeprom_gptr{get,put}N for pointers tagged as data-EEPROM.  The
 * PIC18F452 has 256 bytes of EEPROM (8-bit address), so these forward to the
 * eeprom8 implementations in libsdcc.
 */
extern int __eeprom8_gptrget1;
extern int __eeprom8_gptrget2;
extern int __eeprom8_gptrget3;
extern int __eeprom8_gptrget4;
extern int __eeprom8_gptrput1;
extern int __eeprom8_gptrput2;
extern int __eeprom8_gptrput3;
extern int __eeprom8_gptrput4;

void __eeprom_gptrget1(void) __naked { __asm goto ___eeprom8_gptrget1 __endasm; }
void __eeprom_gptrget2(void) __naked { __asm goto ___eeprom8_gptrget2 __endasm; }
void __eeprom_gptrget3(void) __naked { __asm goto ___eeprom8_gptrget3 __endasm; }
void __eeprom_gptrget4(void) __naked { __asm goto ___eeprom8_gptrget4 __endasm; }
void __eeprom_gptrput1(void) __naked { __asm goto ___eeprom8_gptrput1 __endasm; }
void __eeprom_gptrput2(void) __naked { __asm goto ___eeprom8_gptrput2 __endasm; }
void __eeprom_gptrput3(void) __naked { __asm goto ___eeprom8_gptrput3 __endasm; }
void __eeprom_gptrput4(void) __naked { __asm goto ___eeprom8_gptrput4 __endasm; }
