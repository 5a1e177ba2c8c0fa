//! What to ask of the adapter beyond what it offers, from the caller or the environment.

use anyhow::anyhow;

/// What to ask of the adapter beyond "everything it offers": the paths a given machine would
/// not take on its own. Tests ask for small storage bindings (the chunked paths engage on a
/// mesh of modest size, and wgpu then refuses any binding past the limit, as a GPU with that
/// limit would) and for no timestamp queries (frames without `gpu_ms`, as on adapters that
/// lack them); `scripts/validate.sh` sets the same through the environment
/// ([`DeviceRequest::from_env`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DeviceRequest {
    /// Request at most this `max_storage_buffer_binding_size` (bytes, rounded down to a
    /// multiple of 256, at least 256); `None`: the adapter's own.
    pub max_storage_binding: Option<u64>,
    /// Leave the timestamp-query features off even where the adapter has them.
    pub no_timestamps: bool,
    /// Draw whole meshes in render passes of at most this many triangles (rounded down to a
    /// multiple of 4, at least 4); `None`: [`MAX_TRIANGLES_PER_PASS`](super::MAX_TRIANGLES_PER_PASS).
    pub max_triangles_per_pass: Option<u32>,
}

/// Environment variable of [`DeviceRequest::max_storage_binding`] (bytes).
pub const ENV_MAX_STORAGE_BINDING: &str = "TETBENCH_MAX_STORAGE_BINDING";
/// Environment variable of [`DeviceRequest::no_timestamps`] (`off` turns them off).
pub const ENV_TIMESTAMPS: &str = "TETBENCH_TIMESTAMPS";
/// Environment variable of [`DeviceRequest::max_triangles_per_pass`].
pub const ENV_MAX_TRIANGLES_PER_PASS: &str = "TETBENCH_MAX_TRIANGLES_PER_PASS";

impl DeviceRequest {
    /// The request `TETBENCH_MAX_STORAGE_BINDING=BYTES` and `TETBENCH_TIMESTAMPS=off` describe
    /// (neither set: the adapter as it is).
    pub fn from_env() -> anyhow::Result<DeviceRequest> {
        Self::from_vars(|k| std::env::var(k).ok())
    }

    /// [`DeviceRequest::from_env`] with `lookup` in place of the environment.
    pub fn from_vars(lookup: impl Fn(&str) -> Option<String>) -> anyhow::Result<DeviceRequest> {
        let var = |k: &str| lookup(k).filter(|v| !v.trim().is_empty());
        let max_storage_binding = match var(ENV_MAX_STORAGE_BINDING) {
            None => None,
            Some(v) => Some(v.trim().parse::<u64>().map_err(|_| {
                anyhow!("{ENV_MAX_STORAGE_BINDING}={v:?}: expected a number of bytes")
            })?),
        };
        let no_timestamps = match var(ENV_TIMESTAMPS).as_deref().map(str::trim) {
            None | Some("on") => false,
            Some("off") => true,
            Some(v) => anyhow::bail!("{ENV_TIMESTAMPS}={v:?}: expected on or off"),
        };
        let max_triangles_per_pass = match var(ENV_MAX_TRIANGLES_PER_PASS) {
            None => None,
            Some(v) => Some(v.trim().parse::<u32>().map_err(|_| {
                anyhow!("{ENV_MAX_TRIANGLES_PER_PASS}={v:?}: expected a number of triangles")
            })?),
        };
        Ok(DeviceRequest {
            max_storage_binding,
            no_timestamps,
            max_triangles_per_pass,
        })
    }

    /// What the request changed, for the adapter's description (so that rows measured on a
    /// restricted device say so); empty when nothing.
    pub(super) fn note(&self, limits: &wgpu::Limits) -> String {
        let mut parts = vec![];
        if self.max_storage_binding.is_some() {
            parts.push(format!(
                "max_storage_buffer_binding_size requested as {}",
                limits.max_storage_buffer_binding_size
            ));
        }
        if self.no_timestamps {
            parts.push("timestamp queries off".to_string());
        }
        if let Some(n) = self.max_triangles_per_pass {
            parts.push(format!(
                "render passes of at most {} triangles",
                Self::pass_size(n)
            ));
        }
        parts.join(", ")
    }

    pub(super) fn pass_size(n: u32) -> u32 {
        (n / 4 * 4).max(4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The environment's device request: unset is the adapter as it is; a wrong value is an
    /// error naming the variable.
    #[test]
    fn device_request_from_variables() {
        let vars = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| {
                pairs
                    .iter()
                    .find(|(n, _)| *n == k)
                    .map(|(_, v)| v.to_string())
            }
        };
        assert_eq!(
            DeviceRequest::from_vars(vars(&[])).unwrap(),
            DeviceRequest::default()
        );
        assert_eq!(
            DeviceRequest::from_vars(vars(&[
                (ENV_MAX_STORAGE_BINDING, "262144"),
                (ENV_TIMESTAMPS, "off")
            ]))
            .unwrap(),
            DeviceRequest {
                max_storage_binding: Some(262144),
                no_timestamps: true,
                max_triangles_per_pass: None,
            }
        );
        let e = DeviceRequest::from_vars(vars(&[(ENV_MAX_STORAGE_BINDING, "4k")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("TETBENCH_MAX_STORAGE_BINDING=\"4k\""), "{e}");
        let e = DeviceRequest::from_vars(vars(&[(ENV_TIMESTAMPS, "no")]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("TETBENCH_TIMESTAMPS") && e.contains("on or off"),
            "{e}"
        );
    }
}
