//! NXP's S32K144 (Cortex-M4F, 80 MHz): the modules a board of this ECU brings up, as
//! typed registers reached through an access path ([`crate::chip::access`]), each driver
//! tested on the host for the register sequence it writes (a [`Recorder`] holds the
//! status bits the silicon would set).
//!
//! - [`wdog`]: the watchdog, reconfigured at start-up and then WdgM's;
//! - [`scg`]: the clocks, from the crystal through the SPLL, checked against the chip's
//!   limits before anything is written;
//! - [`flash`]: the flash configuration field at 0x400, checked never to secure the chip;
//! - [`ftm`]: a FlexTimer as the input capture that times the HC-SR04's echo;
//! - [`lpuart`]: the UARTs, as the byte UART the SLCAN controller and the UART sensor
//!   take;
//! - [`pcc`]: each peripheral's clock gate and functional clock;
//! - [`port`]: the pins' functions and the GPIO pins (embedded-hal 1.0 pins).
//!
//! The book: [the NXP boards](../../../../book/nxp-boards.html).
//!
//! Registers and fields as the S32K1xx reference manual (S32K1XXRM) gives them. FlexCAN,
//! shared with the MPC574x chips, is [`crate::chip::flexcan`]. **Nothing here has run on
//! an S32K144**: the tests check what the drivers write, not what the silicon does.
//!
//! [`Recorder`]: crate::chip::access::Recorder

pub mod flash;
pub mod ftm;
pub mod lpuart;
pub mod pcc;
pub mod port;
pub mod scg;
pub mod wdog;
