//! The S32K144's flash configuration field: 16 bytes at 0x400-0x40F of program flash that
//! the chip reads at reset (S32K1xx RM, chapter "Flash Memory Module", "Flash
//! configuration field description"): the backdoor key, the program flash protection,
//! the security byte `FSEC`, the option byte `FOPT`, and the EEPROM and data flash
//! protection.
//!
//! `FSEC` decides whether a debugger may reach the chip. A secured chip whose mass erase
//! is also disabled and whose backdoor key is off can never be erased or reprogrammed
//! again: [`FlashConfig::check`] refuses every secured configuration, so that an image of
//! this project always leaves the chip open to the debugger and to a mass erase.

/// The field's address in program flash.
pub const ADDRESS: u32 = 0x400;

/// The flash configuration field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FlashConfig {
    /// The backdoor comparison key.
    pub backdoor_key: [u8; 8],
    /// `FPROT3`..`FPROT0`: program flash regions protected where a bit is 0.
    pub fprot: [u8; 4],
    /// `FSEC`: security (bits 1..0), factory access (3..2), mass erase (5..4), backdoor
    /// key (7..6).
    pub fsec: u8,
    /// `FOPT`: the boot options.
    pub fopt: u8,
    /// `FEPROT`: EEPROM protection.
    pub feprot: u8,
    /// `FDPROT`: data flash protection.
    pub fdprot: u8,
}

/// A configuration an image must not carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FlashConfigError {
    /// `FSEC[SEC]` is not `10`: the chip would be secured (a debugger locked out).
    Secured(u8),
    /// `FSEC[MEEN]` is `10`: mass erase disabled (with security, the chip is lost).
    MassEraseDisabled(u8),
    /// A region of program flash would be protected against erasing and programming.
    Protected,
}

impl FlashConfig {
    /// What NXP's start-up code writes: no backdoor key, nothing protected, unsecured
    /// (`FSEC` 0xFE: `SEC` 10, mass erase enabled, backdoor disabled), `FOPT` 0x7F.
    pub const UNSECURED: Self = Self {
        backdoor_key: [0xFF; 8],
        fprot: [0xFF; 4],
        fsec: 0xFE,
        fopt: 0x7F,
        feprot: 0xFF,
        fdprot: 0xFF,
    };

    /// The 16 bytes as they lie at 0x400.
    pub const fn bytes(&self) -> [u8; 16] {
        let k = self.backdoor_key;
        let p = self.fprot;
        [
            k[0],
            k[1],
            k[2],
            k[3],
            k[4],
            k[5],
            k[6],
            k[7],
            p[0],
            p[1],
            p[2],
            p[3],
            self.fsec,
            self.fopt,
            self.feprot,
            self.fdprot,
        ]
    }

    /// Whether the chip stays unsecured (`FSEC[SEC]` = `10`).
    pub const fn is_unsecured(&self) -> bool {
        self.fsec & 0b11 == 0b10
    }

    /// Whether a mass erase stays possible (`FSEC[MEEN]` other than `10`).
    pub const fn mass_erase_enabled(&self) -> bool {
        (self.fsec >> 4) & 0b11 != 0b10
    }

    /// The configuration an image may carry: unsecured, mass erase enabled, no program
    /// flash protected.
    ///
    /// # Errors
    /// [`FlashConfigError`] names what would lock the chip or its flash.
    pub const fn check(&self) -> Result<(), FlashConfigError> {
        if !self.is_unsecured() {
            return Err(FlashConfigError::Secured(self.fsec));
        }
        if !self.mass_erase_enabled() {
            return Err(FlashConfigError::MassEraseDisabled(self.fsec));
        }
        let p = self.fprot;
        if p[0] != 0xFF || p[1] != 0xFF || p[2] != 0xFF || p[3] != 0xFF {
            return Err(FlashConfigError::Protected);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unsecured_field_is_what_nxps_start_up_code_writes() {
        // startup_S32K144.S: .long 0xFFFFFFFF (three times), .long 0xFFFF7FFE, little-endian.
        let mut nxp = [0xFF; 16];
        nxp[12..].copy_from_slice(&0xFFFF_7FFE_u32.to_le_bytes());
        assert_eq!(FlashConfig::UNSECURED.bytes(), nxp);
        assert_eq!(FlashConfig::UNSECURED.check(), Ok(()));
    }

    #[test]
    fn every_secured_or_locked_field_is_refused() {
        for fsec in 0..=u8::MAX {
            let c = FlashConfig {
                fsec,
                ..FlashConfig::UNSECURED
            };
            let open = fsec & 0b11 == 0b10 && (fsec >> 4) & 0b11 != 0b10;
            assert_eq!(c.check().is_ok(), open, "FSEC {fsec:#04x}");
        }
        let protected = FlashConfig {
            fprot: [0xFF, 0xFF, 0xFF, 0xFE],
            ..FlashConfig::UNSECURED
        };
        assert_eq!(protected.check(), Err(FlashConfigError::Protected));
        let secured = FlashConfig {
            fsec: 0xFC,
            ..FlashConfig::UNSECURED
        };
        assert_eq!(secured.check(), Err(FlashConfigError::Secured(0xFC)));
    }
}
