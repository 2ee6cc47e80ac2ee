//! RTE building blocks (AUTOSAR SWS RTE): typed sender-receiver communication, last-is-best
//! and queued, with data-received events, and client-server operations.
//!
//! Every port is typed by its *interface* (`SenderReceiverInterface`, `Operation`), not by
//! its data type alone, so connecting a `SonarDataInterface` sender to a
//! `LedRequestInterface` receiver, or reading a `u32` as a `bool`, does not compile. A
//! runnable takes its ports as parameters; the generated (here: hand-written, in firmware)
//! RTE must pass them, so a required port left unconnected does not compile either.
//!
//! A connection declared and used as intended:
//!
//! ```
//! use cw_core::rte::{LastIsBest, SenderReceiverInterface};
//! struct Distance;
//! impl SenderReceiverInterface for Distance {
//!     type Data = u32;
//!     const NAME: &'static str = "Distance";
//! }
//! /// The connections, declared once: every required port is a field.
//! struct Connections {
//!     distance: LastIsBest<Distance>,
//! }
//! /// A receiving runnable names the interface it requires.
//! fn obstacle_detection(port: &LastIsBest<Distance>) -> bool {
//!     port.read() < 1000
//! }
//! let mut rte = Connections { distance: LastIsBest::new(u32::MAX, false) };
//! let _ = rte.distance.write(500);
//! assert!(obstacle_detection(&rte.distance));
//! ```
//!
//! A sender of another interface cannot feed that runnable, even with the same data type:
//!
//! ```compile_fail,E0308
//! use cw_core::rte::{LastIsBest, SenderReceiverInterface};
//! struct Distance;
//! impl SenderReceiverInterface for Distance {
//!     type Data = u32;
//!     const NAME: &'static str = "Distance";
//! }
//! struct Speed;
//! impl SenderReceiverInterface for Speed {
//!     type Data = u32;
//!     const NAME: &'static str = "Speed";
//! }
//! fn obstacle_detection(port: &LastIsBest<Distance>) -> bool {
//!     port.read() < 1000
//! }
//! let speed: LastIsBest<Speed> = LastIsBest::new(0, false);
//! obstacle_detection(&speed);
//! ```
//!
//! Writing the wrong data type into a port does not compile:
//!
//! ```compile_fail,E0308
//! use cw_core::rte::{LastIsBest, SenderReceiverInterface};
//! struct Distance;
//! impl SenderReceiverInterface for Distance {
//!     type Data = u32;
//!     const NAME: &'static str = "Distance";
//! }
//! let mut port: LastIsBest<Distance> = LastIsBest::new(0, false);
//! let _ = port.write(true);
//! ```
//!
//! And a declared connection that is left out does not compile:
//!
//! ```compile_fail,E0063
//! use cw_core::rte::{LastIsBest, SenderReceiverInterface};
//! struct Distance;
//! impl SenderReceiverInterface for Distance {
//!     type Data = u32;
//!     const NAME: &'static str = "Distance";
//! }
//! struct Connections {
//!     distance: LastIsBest<Distance>,
//! }
//! let rte = Connections {};
//! ```
//!
//! Return codes follow `Std_ReturnType`/RTE: [`RteError::NoData`] (`RTE_E_NO_DATA`) when a
//! queue is empty or nothing was ever sent, [`RteError::Limit`] (`RTE_E_LIMIT`) when a queue
//! is full (the value is *not* stored, and the sender knows it).

use core::marker::PhantomData;

/// A sender-receiver interface: a name and the data element's type.
pub trait SenderReceiverInterface {
    /// The data element (copied in and out, as RTE implicit/explicit communication does).
    type Data: Copy;
    /// Interface name, for traces.
    const NAME: &'static str;
}

/// A client-server operation: arguments, result and application error.
pub trait Operation {
    /// Arguments.
    type Args;
    /// Result on success.
    type Output;
    /// Application error (`E_NOT_OK` and friends).
    type Error;
    /// Operation name, for traces.
    const NAME: &'static str;
}

/// The server side of an operation, provided by an SWC or a BSW service.
pub trait Server<O: Operation> {
    /// Runs the operation synchronously in the caller's context (`Rte_Call`).
    ///
    /// # Errors
    /// The operation's application error.
    fn call(&mut self, args: O::Args) -> Result<O::Output, O::Error>;
}

/// RTE return codes other than `RTE_E_OK`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RteError {
    /// `RTE_E_NO_DATA`: nothing to receive.
    NoData,
    /// `RTE_E_LIMIT`: the receiver's queue is full; this value was not stored.
    Limit,
}

/// Whether a write should raise the receiver's data-received event (the RTE then
/// activates the runnable's task).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[must_use = "a data-received event must activate the receiving task"]
pub struct DataReceived(pub bool);

/// A last-is-best connection: the receiver always reads the newest value (or the init
/// value before the first write).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct LastIsBest<I: SenderReceiverInterface> {
    value: I::Data,
    /// Written since the receiver last took it (`Rte_IsUpdated`).
    updated: bool,
    /// Whether a write raises a data-received event.
    event: bool,
    _interface: PhantomData<I>,
}

impl<I: SenderReceiverInterface> LastIsBest<I> {
    /// A connection holding `init` until the first write; `event` says whether writes raise
    /// a data-received event.
    pub const fn new(init: I::Data, event: bool) -> Self {
        Self {
            value: init,
            updated: false,
            event,
            _interface: PhantomData,
        }
    }

    /// `Rte_Write`.
    #[inline(always)]
    pub fn write(&mut self, value: I::Data) -> DataReceived {
        self.value = value;
        self.updated = true;
        DataReceived(self.event)
    }

    /// `Rte_Read`: the newest value (never fails: last-is-best has an init value).
    #[inline(always)]
    pub fn read(&self) -> I::Data {
        self.value
    }

    /// `Rte_IsUpdated`.
    pub const fn is_updated(&self) -> bool {
        self.updated
    }

    /// Reads and marks the value as taken; [`RteError::NoData`] if nothing new arrived.
    ///
    /// # Errors
    /// [`RteError::NoData`].
    pub fn take(&mut self) -> Result<I::Data, RteError> {
        if !self.updated {
            return Err(RteError::NoData);
        }
        self.updated = false;
        Ok(self.value)
    }
}

/// A queued connection of capacity `N`: every value is received once, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Queued<I: SenderReceiverInterface, const N: usize> {
    slots: [Option<I::Data>; N],
    head: usize,
    len: usize,
    /// Values refused because the queue was full (`RTE_E_LIMIT` returned each time).
    refused: u32,
    _interface: PhantomData<I>,
}

impl<I: SenderReceiverInterface, const N: usize> Queued<I, N> {
    /// An empty queue.
    pub const fn new() -> Self {
        Self {
            slots: [None; N],
            head: 0,
            len: 0,
            refused: 0,
            _interface: PhantomData,
        }
    }

    /// `Rte_Send`: appends a value; raises the data-received event.
    ///
    /// # Errors
    /// [`RteError::Limit`] when full; the value is not stored.
    pub fn send(&mut self, value: I::Data) -> Result<DataReceived, RteError> {
        if self.len >= N {
            self.refused = self.refused.saturating_add(1);
            return Err(RteError::Limit);
        }
        let slot = (self.head + self.len) % N;
        self.slots[slot] = Some(value);
        self.len += 1;
        Ok(DataReceived(true))
    }

    /// `Rte_Receive`: the oldest value.
    ///
    /// # Errors
    /// [`RteError::NoData`] when empty.
    pub fn receive(&mut self) -> Result<I::Data, RteError> {
        if self.len == 0 {
            return Err(RteError::NoData);
        }
        let value = self
            .slots
            .get_mut(self.head)
            .and_then(Option::take)
            .ok_or(RteError::NoData)?;
        self.head = (self.head + 1) % N;
        self.len -= 1;
        Ok(value)
    }

    /// Values waiting.
    pub const fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing waits.
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Values refused with `RTE_E_LIMIT` so far.
    pub const fn refused(&self) -> u32 {
        self.refused
    }
}

impl<I: SenderReceiverInterface, const N: usize> Default for Queued<I, N> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;

    struct SonarData;
    impl SenderReceiverInterface for SonarData {
        type Data = u32;
        const NAME: &'static str = "SonarDataInterface";
    }

    struct Add;
    impl Operation for Add {
        type Args = (u8, u8);
        type Output = u8;
        type Error = ();
        const NAME: &'static str = "Add";
    }
    struct Adder;
    impl Server<Add> for Adder {
        fn call(&mut self, (a, b): (u8, u8)) -> Result<u8, ()> {
            a.checked_add(b).ok_or(())
        }
    }

    #[test]
    fn last_is_best_keeps_the_newest_and_reports_updates() {
        let mut port = LastIsBest::<SonarData>::new(0, true);
        assert_eq!(port.read(), 0);
        assert_eq!(port.take(), Err(RteError::NoData));
        assert_eq!(port.write(1500), DataReceived(true));
        let _ = port.write(900);
        assert!(port.is_updated());
        assert_eq!(port.take(), Ok(900));
        assert_eq!(port.take(), Err(RteError::NoData));
        assert_eq!(port.read(), 900, "reading stays possible");
        let mut quiet = LastIsBest::<SonarData>::new(7, false);
        assert_eq!(quiet.write(1), DataReceived(false));
    }

    #[test]
    fn queue_keeps_order_and_refuses_when_full() {
        let mut q = Queued::<SonarData, 2>::new();
        assert_eq!(q.receive(), Err(RteError::NoData));
        assert_eq!(q.send(1), Ok(DataReceived(true)));
        assert_eq!(q.send(2), Ok(DataReceived(true)));
        assert_eq!(q.send(3), Err(RteError::Limit));
        assert_eq!(q.refused(), 1);
        assert_eq!(q.receive(), Ok(1));
        assert_eq!(q.send(4), Ok(DataReceived(true)));
        assert_eq!(
            (q.receive(), q.receive(), q.receive()),
            (Ok(2), Ok(4), Err(RteError::NoData))
        );
    }

    #[test]
    fn client_server_call() {
        fn client(server: &mut impl Server<Add>) -> Result<u8, ()> {
            server.call((200, 55))
        }
        assert_eq!(client(&mut Adder), Ok(255));
        assert_eq!(Adder.call((200, 56)), Err(()));
    }

    /// Any interleaving of sends and receives: the queue delivers exactly the accepted
    /// values, in order.
    #[test]
    fn queue_is_fifo_for_any_interleaving() {
        bolero::check!()
            .with_type::<std::vec::Vec<Option<u32>>>()
            .for_each(|ops| {
                let mut q = Queued::<SonarData, 3>::new();
                let mut model = std::collections::VecDeque::new();
                for op in ops {
                    match op {
                        Some(v) => match q.send(*v) {
                            Ok(_) => model.push_back(*v),
                            Err(e) => {
                                assert_eq!(e, RteError::Limit);
                                assert_eq!(model.len(), 3);
                            }
                        },
                        None => assert_eq!(q.receive().ok(), model.pop_front()),
                    }
                }
            });
    }
}
