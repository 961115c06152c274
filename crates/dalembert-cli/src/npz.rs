//! NumPy's `.npz` archive, written without a dependency: a zip archive (stored, not compressed)
//! of `.npy` files, as `numpy.savez` writes it and `numpy.load` reads it (the formats: NumPy
//! Enhancement Proposal 1, "A simple file format for NumPy arrays", and PKWARE's APPNOTE for zip).
//! `linearize --output lin.npz` writes its matrices this way.

/// One array of an archive: float64 values in C order with their shape, or a list of strings
/// (NumPy's fixed-width unicode, `<U`).
pub enum Array<'a> {
    /// Values (C order) and shape.
    Numbers(Vec<f64>, Vec<usize>),
    /// A one-dimensional array of strings.
    Strings(&'a [String]),
}

/// The `.npy` file of `array` (format version 1.0).
fn npy(array: &Array<'_>) -> Vec<u8> {
    let (descr, shape, data): (String, Vec<usize>, Vec<u8>) = match array {
        Array::Numbers(values, shape) => (
            "<f8".into(),
            shape.clone(),
            values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        ),
        Array::Strings(items) => {
            let width = items.iter().map(|s| s.chars().count()).max().unwrap_or(0).max(1);
            let mut data = Vec::with_capacity(4 * width * items.len());
            for s in items.iter() {
                let n = s.chars().count();
                data.extend(s.chars().flat_map(|c| (c as u32).to_le_bytes()));
                data.extend(std::iter::repeat_n(0u8, 4 * (width - n)));
            }
            (format!("<U{width}"), vec![items.len()], data)
        }
    };
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let shape = match dims.len() {
        1 => format!("({},)", dims[0]),
        _ => format!("({})", dims.join(", ")),
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    // Magic (6), version (2) and the header's length (2), then the header padded with spaces and
    // ended by a newline so that the data starts on a multiple of 64 bytes.
    let used = 10 + header.len() + 1;
    header.extend(std::iter::repeat_n(' ', (64 - used % 64) % 64));
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend((header.len() as u16).to_le_bytes());
    out.extend(header.as_bytes());
    out.extend(data);
    out
}

/// CRC-32 (IEEE 802.3, reflected, as zip uses it) of `bytes`.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// The archive of `arrays` (each named `<name>.npy` inside, loaded by `numpy.load` as `name`).
pub fn archive(arrays: &[(&str, Array<'_>)]) -> Vec<u8> {
    let (mut out, mut directory) = (Vec::new(), Vec::new());
    let entries = arrays.len() as u16;
    for (name, array) in arrays {
        let data = npy(array);
        let file = format!("{name}.npy");
        let (crc, size, offset) = (crc32(&data), data.len() as u32, out.len() as u32);
        // Version 2.0 needed, no flags, stored, 1980-01-01 00:00.
        let common = |sig: u32, central: bool| {
            let mut h = sig.to_le_bytes().to_vec();
            if central {
                h.extend(20u16.to_le_bytes());
            }
            for x in [20u16, 0, 0, 0, 0x21] {
                h.extend(x.to_le_bytes());
            }
            h.extend(crc.to_le_bytes());
            h.extend(size.to_le_bytes());
            h.extend(size.to_le_bytes());
            h.extend((file.len() as u16).to_le_bytes());
            h.extend(0u16.to_le_bytes());
            h
        };
        out.extend(common(0x0403_4b50, false));
        out.extend(file.as_bytes());
        out.extend(&data);
        let mut c = common(0x0201_4b50, true);
        // No comment, disk 0, no attributes, the local header's offset.
        for x in [0u16, 0, 0] {
            c.extend(x.to_le_bytes());
        }
        c.extend(0u32.to_le_bytes());
        c.extend(offset.to_le_bytes());
        c.extend(file.as_bytes());
        directory.extend(c);
    }
    let start = out.len() as u32;
    out.extend(&directory);
    out.extend(0x0605_4b50u32.to_le_bytes());
    for x in [0u16, 0, entries, entries] {
        out.extend(x.to_le_bytes());
    }
    out.extend((directory.len() as u32).to_le_bytes());
    out.extend(start.to_le_bytes());
    out.extend(0u16.to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_of_the_standard_check_string() {
        // The check value of CRC-32/ISO-HDLC (the zip CRC) for "123456789".
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn a_npy_header_pads_the_data_to_64_bytes() {
        let bytes = npy(&Array::Numbers(vec![1.0, 2.0], vec![1, 2]));
        let header = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + header) % 64, 0);
        assert_eq!(
            &bytes[10 + header..],
            [1.0f64.to_le_bytes(), 2.0f64.to_le_bytes()].concat()
        );
    }
}
