//! Shard files: one contiguous range of a distributed computation's items (table cells,
//! Monte-Carlo samples), made safe to trust. A shard may come from a node that crashed, an
//! earlier run with another grid, or a half-copied directory, so every file carries
//!
//! * the kind of computation and the **identity** of its inputs (SHA-256 of the grid or study
//!   configuration): shards of another grid are refused;
//! * its K/N, its item range and the total item count: the range must be the one K/N gives,
//!   and a set of shards must tile `0..total` exactly (no gap, no overlap);
//! * its own checksum: the envelope of the diagram file format (magic, version, length,
//!   CRC-32C; [`diagram::frame`]), so truncation and bit rot are found before decoding.
//!
//! Every error names the file and the reason.

use anyhow::{anyhow, bail, Context, Result};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::ops::Range;

/// Magic number of shard files (`\x89RLSH\r\n\x1a`: restraint LUT shard).
pub const SHARD_MAGIC: [u8; 8] = [0x89, b'R', b'L', b'S', b'H', b'\r', b'\n', 0x1A];
/// Shard file version (1 was the unframed postcard shard of earlier builds).
pub const SHARD_VERSION: u16 = 2;
/// What a bad magic number is reported as not being.
const SHARD_FILE_KIND: &str = "LUT shard";

/// Contiguous index range of shard `k` of `n` (1-based k) over `count` items:
/// `[count·(k−1)/n, count·k/n)`.
pub fn shard_range(count: usize, k: usize, n: usize) -> Result<Range<usize>> {
    if n == 0 || k == 0 || k > n {
        bail!("shard {k}/{n}: need 1 ≤ K ≤ N");
    }
    let start = count * (k - 1) / n;
    let end = count * k / n;
    Ok(start..end)
}

/// Hex SHA-256 of `kind` and the postcard encoding of `inputs`: the identity of a
/// computation's inputs (deterministic: postcard has one encoding per value).
pub fn identity_of<T: Serialize + ?Sized>(kind: &str, inputs: &T) -> Result<String> {
    let bytes = postcard::to_allocvec(inputs).context("encoding inputs for the identity hash")?;
    let mut h = Sha256::new();
    h.update(kind.as_bytes());
    h.update([0u8]);
    h.update(&bytes);
    Ok(h.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

/// What a shard is, independent of its payload.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardHeader {
    /// Kind of computation ("table", "robustness").
    pub kind: String,
    /// Identity of the inputs ([`identity_of`]).
    pub identity: String,
    /// Shard number K (1-based).
    pub k: u32,
    /// Shard count N.
    pub n: u32,
    /// First item.
    pub start: u64,
    /// One past the last item.
    pub end: u64,
    /// Items of the whole computation.
    pub total: u64,
}

impl ShardHeader {
    /// Header of shard `k` of `n` over `total` items.
    pub fn new(kind: &str, identity: &str, k: usize, n: usize, total: usize) -> Result<Self> {
        let r = shard_range(total, k, n)?;
        Ok(ShardHeader {
            kind: kind.into(),
            identity: identity.into(),
            k: u32::try_from(k)?,
            n: u32::try_from(n)?,
            start: r.start as u64,
            end: r.end as u64,
            total: total as u64,
        })
    }

    /// The item range.
    pub fn range(&self) -> Range<usize> {
        self.start as usize..self.end as usize
    }

    /// "shard K/N (items a..b)".
    pub fn describe(&self) -> String {
        format!(
            "shard {}/{} (items {}..{})",
            self.k, self.n, self.start, self.end
        )
    }
}

/// Payloads know how many items they hold (checked against the header's range).
pub trait Payload {
    /// Number of items.
    fn item_count(&self) -> usize;
}

/// A shard file: header plus payload.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardFile<P> {
    /// What the shard is.
    pub header: ShardHeader,
    /// The items.
    pub payload: P,
}

impl<P: Serialize + DeserializeOwned + Payload> ShardFile<P> {
    /// Encode: postcard inside the checksummed envelope.
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let payload = postcard::to_allocvec(self).context("encoding shard")?;
        Ok(diagram::frame(&SHARD_MAGIC, SHARD_VERSION, &payload))
    }

    /// Decode and check one file on its own: envelope and checksum, kind, a range that is the
    /// one its K/N gives, and the payload's item count. `origin` names the file in errors.
    pub fn from_bytes(origin: &str, kind: &str, bytes: &[u8]) -> Result<Self> {
        let payload = diagram::unframe(&SHARD_MAGIC, SHARD_FILE_KIND, SHARD_VERSION, bytes)
            .map_err(|e| anyhow!("{origin}: corrupt shard file: {e}"))?;
        let s: ShardFile<P> = postcard::from_bytes(payload)
            .map_err(|e| anyhow!("{origin}: corrupt shard file: payload does not decode: {e}"))?;
        let h = &s.header;
        if h.kind != kind {
            bail!("{origin}: a {:?} shard, not a {kind:?} shard", h.kind);
        }
        let expect = shard_range(h.total as usize, h.k as usize, h.n as usize)
            .map_err(|e| anyhow!("{origin}: {e}"))?;
        if h.range() != expect {
            bail!(
                "{origin}: shard {}/{} claims items {}..{}, but {}/{} of {} items is {expect:?}",
                h.k,
                h.n,
                h.start,
                h.end,
                h.k,
                h.n,
                h.total
            );
        }
        if s.payload.item_count() != expect.len() {
            bail!(
                "{origin}: {} holds {} items, its range {expect:?} needs {}",
                h.describe(),
                s.payload.item_count(),
                expect.len()
            );
        }
        Ok(s)
    }
}

/// Check that a set of shards belongs together and tiles `0..total` exactly: the same kind,
/// identity (`expected`, or the first shard's) and total; no overlap; no gap. Errors name the
/// files. Returns the shards' order by range.
pub fn check_tiling(shards: &[(&str, &ShardHeader)], expected: Option<&str>) -> Result<Vec<usize>> {
    let (first_origin, first) = shards.first().ok_or_else(|| anyhow!("no shard given"))?;
    let identity = expected.unwrap_or(&first.identity);
    for (origin, h) in shards {
        if h.identity != identity {
            let whose = match expected {
                Some(_) => "this computation's".to_string(),
                None => format!("{first_origin}'s"),
            };
            bail!(
                "{origin}: shard of another grid or configuration (identity {}…, {whose} is {}…)",
                short(&h.identity),
                short(identity)
            );
        }
        if h.kind != first.kind || h.total != first.total {
            bail!(
                "{origin}: {} shard of {} items does not belong with {first_origin} ({} shard of {} items)",
                h.kind,
                h.total,
                first.kind,
                first.total
            );
        }
    }
    let mut order: Vec<usize> = (0..shards.len()).collect();
    order.sort_by_key(|&i| (shards[i].1.start, shards[i].1.end));
    let mut next = 0u64;
    let mut prev: Option<&str> = None;
    for &i in &order {
        let (origin, h) = shards[i];
        if h.start > next {
            bail!(
                "items {next}..{} missing: no shard covers them (between {} and {origin})",
                h.start,
                prev.unwrap_or("the start")
            );
        }
        if h.start < next {
            bail!(
                "{origin} ({}) overlaps {} on items {}..{next}",
                h.describe(),
                prev.unwrap_or("?"),
                h.start
            );
        }
        next = h.end;
        prev = Some(origin);
    }
    if next != first.total {
        bail!(
            "items {next}..{} missing: no shard covers them (after {})",
            first.total,
            prev.unwrap_or("the start")
        );
    }
    Ok(order)
}

/// First 12 hex digits of an identity (for messages).
pub fn short(identity: &str) -> &str {
    identity.get(..12).unwrap_or(identity)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    struct Items(Vec<u32>);
    impl Payload for Items {
        fn item_count(&self) -> usize {
            self.0.len()
        }
    }

    fn shard(id: &str, k: usize, n: usize, total: usize) -> ShardFile<Items> {
        let header = ShardHeader::new("t", id, k, n, total).unwrap();
        let payload = Items(header.range().map(|i| i as u32).collect());
        ShardFile { header, payload }
    }

    #[test]
    fn round_trip_and_corruption_is_named() {
        let s = shard("abc", 2, 3, 10);
        let bytes = s.to_bytes().unwrap();
        assert_eq!(ShardFile::<Items>::from_bytes("f", "t", &bytes).unwrap(), s);
        for i in [0, 9, 17, 25, bytes.len() - 1] {
            let mut bad = bytes.clone();
            bad[i] ^= 0x10;
            let e = ShardFile::<Items>::from_bytes("dir/x.bin", "t", &bad).unwrap_err();
            assert!(e.to_string().starts_with("dir/x.bin: "), "{e}");
        }
        let e = ShardFile::<Items>::from_bytes("f", "t", &bytes[..bytes.len() - 1]).unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
        let e = ShardFile::<Items>::from_bytes("f", "other", &bytes).unwrap_err();
        assert!(e.to_string().contains("not a \"other\" shard"), "{e}");
    }

    #[test]
    fn a_lying_range_or_item_count_is_refused() {
        let mut s = shard("abc", 2, 3, 10);
        s.header.end += 1;
        let e = ShardFile::<Items>::from_bytes("f", "t", &s.to_bytes().unwrap()).unwrap_err();
        assert!(e.to_string().contains("claims items 3..7"), "{e}");
        let mut s = shard("abc", 2, 3, 10);
        s.payload.0.pop();
        let e = ShardFile::<Items>::from_bytes("f", "t", &s.to_bytes().unwrap()).unwrap_err();
        assert!(
            e.to_string()
                .contains("holds 2 items, its range 3..6 needs 3"),
            "{e}"
        );
    }

    #[test]
    fn tiling_names_gaps_overlaps_and_foreign_shards() {
        let a = shard("id", 1, 3, 10).header;
        let b = shard("id", 2, 3, 10).header;
        let c = shard("id", 3, 3, 10).header;
        assert_eq!(
            check_tiling(&[("c", &c), ("a", &a), ("b", &b)], Some("id")).unwrap(),
            vec![1, 2, 0]
        );
        let e = check_tiling(&[("a", &a), ("c", &c)], None).unwrap_err();
        assert_eq!(
            e.to_string(),
            "items 3..6 missing: no shard covers them (between a and c)"
        );
        let e = check_tiling(&[("a", &a), ("b", &b)], None).unwrap_err();
        assert!(e.to_string().contains("items 6..10 missing"), "{e}");
        // Shards of two different N that overlap.
        let half = shard("id", 1, 2, 10).header;
        let e =
            check_tiling(&[("a", &a), ("half", &half), ("b", &b), ("c", &c)], None).unwrap_err();
        assert!(e.to_string().contains("overlaps"), "{e}");
        let other = shard("other", 2, 3, 10).header;
        let e = check_tiling(&[("a", &a), ("o.bin", &other), ("c", &c)], Some("id")).unwrap_err();
        assert!(
            e.to_string().starts_with("o.bin: shard of another grid"),
            "{e}"
        );
        // Shards of different N that tile exactly are fine.
        let h2 = shard("id", 2, 2, 10).header;
        let q1 = shard("id", 1, 4, 10).header;
        let q2 = shard("id", 2, 4, 10).header;
        check_tiling(&[("h2", &h2), ("q1", &q1), ("q2", &q2)], None).unwrap();
    }

    #[test]
    fn identity_depends_on_kind_and_inputs() {
        let a = identity_of("table", &(1u32, "x")).unwrap();
        assert_eq!(a.len(), 64);
        assert_eq!(a, identity_of("table", &(1u32, "x")).unwrap());
        assert_ne!(a, identity_of("table", &(2u32, "x")).unwrap());
        assert_ne!(a, identity_of("robustness", &(1u32, "x")).unwrap());
    }
}
