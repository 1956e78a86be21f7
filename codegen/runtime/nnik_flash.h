/*
 * nnik_flash.h - constant tables in program memory, portably.
 *
 *   static NNIK_FLASH const int16_t tab[] = { ... };   definition (file or block scope,
 *                                                      static storage duration)
 *   NNIK_RD_U8(&tab[i]), NNIK_RD_I16(&tab[i]), NNIK_RD_U16(&tab[i]), NNIK_RD_I32(&tab[i])
 *                                                      read one element
 *
 * The qualifier goes on the object definition, before the type:
 *   avr-gcc        PROGMEM (section .progmem), read with pgm_read_byte/word/dword (LPM)
 *   SDCC (pic16 and the other ports)
 *                  __code, read by plain dereference (the compiler emits TBLRD on pic16)
 *   XC8            nothing: static const objects already live in program memory
 *   anything else  nothing (plain const data), plain dereference
 *
 * Define NNIK_FLASH and the NNIK_RD_* macros yourself before including this header to
 * override the choice (e.g. to keep the tables in RAM on an AVR for speed).
 */
#ifndef NNIK_FLASH_H
#define NNIK_FLASH_H

#include <stdint.h>

#ifndef NNIK_FLASH

#if defined(__AVR__) && defined(__GNUC__)
#include <avr/pgmspace.h>
#define NNIK_FLASH PROGMEM
#define NNIK_FLASH_AVR_PROGMEM 1 /* tables are read with LPM (nnik_kernel.h relies on it) */
#define NNIK_RD_U8(p) ((uint8_t)pgm_read_byte(p))
#define NNIK_RD_U16(p) ((uint16_t)pgm_read_word(p))
#define NNIK_RD_I16(p) ((int16_t)pgm_read_word(p))
#define NNIK_RD_I32(p) ((int32_t)pgm_read_dword(p))

#elif defined(__SDCC) || defined(SDCC)
/* __SDCC_pic16 and the other SDCC ports: the __code address space. */
#define NNIK_FLASH __code
#define NNIK_FLASH_SDCC_CODE 1 /* tables are in __code (nnik_kernel.h's PIC18 path reads them with TBLRD) */

#elif defined(__XC8) || defined(__XC8__)
#define NNIK_FLASH

#else
#define NNIK_FLASH
#endif

#endif /* NNIK_FLASH */

/* Plain dereference where the platform did not define a reader. */
#ifndef NNIK_RD_U8
#define NNIK_RD_U8(p) (*(p))
#endif
#ifndef NNIK_RD_U16
#define NNIK_RD_U16(p) (*(p))
#endif
#ifndef NNIK_RD_I16
#define NNIK_RD_I16(p) (*(p))
#endif
#ifndef NNIK_RD_I32
#define NNIK_RD_I32(p) (*(p))
#endif

#endif /* NNIK_FLASH_H */
