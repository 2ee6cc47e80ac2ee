//! How a module reaches its configuration tables.
//!
//! Every BSW module takes its validated configuration as a type parameter `C: Tables<T>`.
//! Two kinds of `C` exist:
//!
//! - `&'static T`, a reference chosen at run time: one compiled module serves any
//!   configuration (the unit tests, the model checker and the fuzz targets use this);
//! - a zero-sized type declared with [`static_tables!`](crate::static_tables!) that names one `static`: every
//!   lookup of a constant id then folds to the configured value at build time, so a layer
//!   costs only the work its configuration asks for. This is AUTOSAR's pre-compile
//!   configuration variant; the ECU uses it.
//!
//! The module code is the same for both; only the cost of reading the tables differs.

/// A source of `'static` configuration tables of type `T`.
///
/// The comparison and hashing traits let module state that holds a `Tables` value derive
/// them (the model checker hashes kernel states).
pub trait Tables<T: 'static>: Copy + Eq + core::hash::Hash + core::fmt::Debug {
    /// The tables.
    fn tables(self) -> &'static T;
}

impl<T: 'static + Eq + core::hash::Hash + core::fmt::Debug> Tables<T> for &'static T {
    #[inline(always)]
    fn tables(self) -> &'static T {
        self
    }
}

/// Declares a zero-sized [`Tables`] type for a `static` configuration:
/// `static_tables!(pub ComTables: ComConfig<8, 1, 1, 4> = COM);`.
#[macro_export]
macro_rules! static_tables {
    ($(#[$meta:meta])* $vis:vis $name:ident: $ty:ty = $table:path) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        $vis struct $name;

        impl $crate::tables::Tables<$ty> for $name {
            #[inline(always)]
            fn tables(self) -> &'static $ty {
                &$table
            }
        }
    };
}
