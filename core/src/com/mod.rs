//! AUTOSAR communication services (Com). This part is the signal codec
//! ([`signal`]): how a signal value is placed into and read out of an I-PDU.
pub mod signal;
