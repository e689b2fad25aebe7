//! CRC-32C (Castagnoli, reflected polynomial 0x82F63B78, initial value and final XOR
//! 0xFFFFFFFF), as in iSCSI and ext4. Check value: CRC-32C("123456789") = 0xE3069283.

/// Incremental CRC-32C (the `crc32c` crate: SSE 4.2 / ARMv8 instructions where the CPU
/// has them, tables otherwise).
pub struct Crc32c(u32);

impl Default for Crc32c {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32c {
    pub fn new() -> Self {
        Crc32c(0)
    }
    pub fn update(&mut self, data: &[u8]) {
        self.0 = crc32c::crc32c_append(self.0, data);
    }
    pub fn finish(&self) -> u32 {
        self.0
    }
}

/// CRC-32C of `data`.
pub fn crc32c(data: &[u8]) -> u32 {
    crc32c::crc32c(data)
}

#[cfg(test)]
mod tests {
    #[test]
    fn check_value() {
        assert_eq!(super::crc32c(b"123456789"), 0xE306_9283);
    }
}
