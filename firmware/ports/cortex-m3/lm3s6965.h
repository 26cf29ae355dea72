/* lm3s6965: the few registers of the Stellaris LM3S6965 (Cortex-M3) this port uses, from the
 * LM3S6965 data sheet (Texas Instruments DS-LM3S6965) and the ARMv7-M Architecture Reference
 * Manual (SysTick, NVIC, SCB). Only what qemu's lm3s6965evb board models and a real chip needs. */
#ifndef LM3S6965_H
#define LM3S6965_H

#include <stdint.h>

#define REG32(addr) (*(volatile uint32_t *)(uintptr_t)(addr))

/* System control: run-mode clock gating and the clock tree (data sheet 6.4). */
#define SYSCTL_RIS           REG32(0x400FE050u)
#define SYSCTL_RCC           REG32(0x400FE060u)
#define SYSCTL_RCGC1         REG32(0x400FE104u)
#define SYSCTL_RCGC2         REG32(0x400FE108u)
#define SYSCTL_RIS_PLLLRIS   (1u << 6)
#define SYSCTL_RCC_SYSDIV_S  23
#define SYSCTL_RCC_SYSDIV_M  (0xFu << 23)
#define SYSCTL_RCC_USESYSDIV (1u << 22)
#define SYSCTL_RCC_PWRDN     (1u << 13)
#define SYSCTL_RCC_BYPASS    (1u << 11)
#define SYSCTL_RCC_XTAL_M    (0xFu << 6)
#define SYSCTL_RCC_XTAL_8MHZ (0xEu << 6)
#define SYSCTL_RCC_OSCSRC_M  (0x3u << 4)
#define SYSCTL_RCGC1_TIMER0  (1u << 16)
#define SYSCTL_RCGC1_UART0   (1u << 0)
#define SYSCTL_RCGC1_TIMER1  (1u << 17)
#define SYSCTL_RCGC1_TIMER2  (1u << 18)
#define SYSCTL_RCGC2_GPIOA   (1u << 0)
#define SYSCTL_RCGC2_GPIOD   (1u << 3)
#define SYSCTL_RCGC2_GPIOG   (1u << 6)

/* GPIO ports (PL061-like): DATA is addressed through a mask in address bits 9:2. */
#define GPIO_PORTA            0x40004000u
#define GPIO_PORTD            0x40007000u
#define GPIO_PORTG            0x40026000u
#define GPIO_DATA(port, mask) REG32((port) + ((uint32_t)(mask) << 2))
#define GPIO_DIR(port)        REG32((port) + 0x400u)
#define GPIO_AFSEL(port)      REG32((port) + 0x420u)
#define GPIO_DEN(port)        REG32((port) + 0x51Cu)

/* Machine control (port_m3_ctl.c): GPIO ports B, C, E, F, their interrupt and pull-up
 * registers (data sheet 8.5), the PWM module's generator 0 (data sheet 20.6) and its clock gate. */
#define SYSCTL_RCGC0         REG32(0x400FE100u)
#define SYSCTL_RCGC0_PWM     (1u << 20)
#define SYSCTL_RCGC2_GPIOB   (1u << 1)
#define SYSCTL_RCGC2_GPIOC   (1u << 2)
#define SYSCTL_RCGC2_GPIOE   (1u << 4)
#define SYSCTL_RCGC2_GPIOF   (1u << 5)
#define GPIO_PORTB           0x40005000u
#define GPIO_PORTC           0x40006000u
#define GPIO_PORTE           0x40024000u
#define GPIO_PORTF           0x40025000u
#define GPIO_IS(port)        REG32((port) + 0x404u)
#define GPIO_IBE(port)       REG32((port) + 0x408u)
#define GPIO_IM(port)        REG32((port) + 0x410u)
#define GPIO_ICR(port)       REG32((port) + 0x41Cu)
#define GPIO_PUR(port)       REG32((port) + 0x510u)
#define GPIO_PDR(port)       REG32((port) + 0x514u)
#define GPIOB_IRQ            1
#define GPIOE_IRQ            4
#define PWM_BASE             0x40028000u
#define PWM_ENABLE           REG32(PWM_BASE + 0x008u)
#define PWM0_CTL             REG32(PWM_BASE + 0x040u)
#define PWM0_LOAD            REG32(PWM_BASE + 0x050u)
#define PWM0_CMPA            REG32(PWM_BASE + 0x058u)
#define PWM0_GENA            REG32(PWM_BASE + 0x060u)
#define PWM_GEN_ENABLE       (1u << 0)
#define PWM_GENA_LOAD_HIGH   (3u << 2) /* ACTLOAD: drive high at the load (count-down mode) */
#define PWM_GENA_CMPAD_LOW   (2u << 6) /* ACTCMPAD: drive low at compare A counting down */

/* UART0 (ARM PrimeCell PL011), IRQ 5. */
#define UART0           0x4000C000u
#define UART_DR         REG32(UART0 + 0x000u)
#define UART_FR         REG32(UART0 + 0x018u)
#define UART_IBRD       REG32(UART0 + 0x024u)
#define UART_FBRD       REG32(UART0 + 0x028u)
#define UART_LCRH       REG32(UART0 + 0x02Cu)
#define UART_CTL        REG32(UART0 + 0x030u)
#define UART_IFLS       REG32(UART0 + 0x034u)
#define UART_IM         REG32(UART0 + 0x038u)
#define UART_MIS        REG32(UART0 + 0x040u)
#define UART_ICR        REG32(UART0 + 0x044u)
#define UART_FR_RXFE    (1u << 4)
#define UART_FR_TXFF    (1u << 5)
#define UART_LCRH_WLEN8 (3u << 5)
#define UART_LCRH_FEN   (1u << 4)
#define UART_CTL_UARTEN (1u << 0)
#define UART_CTL_TXE    (1u << 8)
#define UART_CTL_RXE    (1u << 9)
#define UART_INT_RX     (1u << 4)
#define UART_INT_TX     (1u << 5)
#define UART_INT_RT     (1u << 6)
#define UART0_IRQ       5

/* General-purpose timer 0 (GPTM), timer A in 32-bit one-shot mode, IRQ 19. */
#define TIMER0             0x40030000u
#define TIMER_CFG          REG32(TIMER0 + 0x00u)
#define TIMER_TAMR         REG32(TIMER0 + 0x04u)
#define TIMER_CTL          REG32(TIMER0 + 0x0Cu)
#define TIMER_IMR          REG32(TIMER0 + 0x18u)
#define TIMER_ICR          REG32(TIMER0 + 0x24u)
#define TIMER_TAILR        REG32(TIMER0 + 0x28u)
#define TIMER_TAMR_ONESHOT 1u
#define TIMER_CTL_TAEN     (1u << 0)
#define TIMER_INT_TATO     (1u << 0)
#define TIMER0A_IRQ        19

/* The same registers on any GPTM (Timer1 at 0x40031000, Timer2 at 0x40032000; data sheet 9.5):
 * the pen servo's period (Timer1A, 32-bit periodic, IRQ 21) and width (Timer2A, one-shot, IRQ 23). */
#define TIMER1              0x40031000u
#define TIMER2              0x40032000u
#define GPTM_CFG(t)         REG32((t) + 0x00u)
#define GPTM_TAMR(t)        REG32((t) + 0x04u)
#define GPTM_CTL(t)         REG32((t) + 0x0Cu)
#define GPTM_IMR(t)         REG32((t) + 0x18u)
#define GPTM_ICR(t)         REG32((t) + 0x24u)
#define GPTM_TAILR(t)       REG32((t) + 0x28u)
#define TIMER_TAMR_PERIODIC 2u
#define TIMER1A_IRQ         21
#define TIMER2A_IRQ         23

/* Cortex-M3 core peripherals (ARMv7-M ARM B3.3, B3.4). */
#define SYST_CSR           REG32(0xE000E010u)
#define SYST_RVR           REG32(0xE000E014u)
#define SYST_CVR           REG32(0xE000E018u)
#define SYST_CSR_ENABLE    (1u << 0)
#define SYST_CSR_TICKINT   (1u << 1)
#define SYST_CSR_CLKSOURCE (1u << 2)
#define NVIC_ISER(n)       REG32(0xE000E100u + 4u * (n))
#define NVIC_IPR(n)        (*(volatile uint8_t *)(uintptr_t)(0xE000E400u + (n)))
#define SCB_ICSR           REG32(0xE000ED04u)
#define SCB_ICSR_PENDSTSET (1u << 26)
#define SCB_SHPR3          REG32(0xE000ED20u)

#endif
