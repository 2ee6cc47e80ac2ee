//! AUTOSAR communication services (Com): the signal codec ([`signal`]), which places a
//! signal value into an I-PDU and reads it back, and the I-PDU layer ([`ipdu`]):
//! send/receive signal, transmission modes, update bits, deadline monitoring and the main
//! functions.
pub mod ipdu;
pub mod signal;
