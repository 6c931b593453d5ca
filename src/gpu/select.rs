//! Which Vulkan adapter renders: `--adapter` (an index of `wgtrace info`, or part of a
//! name), else the GPU a cluster's scheduler assigned through `CUDA_VISIBLE_DEVICES`,
//! `ROCR_VISIBLE_DEVICES` or `HIP_VISIBLE_DEVICES`, else the preferred adapter (index 0).
//! Vulkan ignores those variables, so without this every task of a 4-GPU node would
//! render on adapter 0.
//!
//! An index in such a variable counts the vendor's GPUs in PCI bus order (what nvidia-smi
//! shows, and CUDA with `CUDA_DEVICE_ORDER=PCI_BUS_ID`; Slurm's gres numbers them so); a
//! UUID (`GPU-5f2e...`) is matched against Vulkan's device UUID, which NVIDIA's driver
//! makes equal to CUDA's. The first device of the list renders: one per process.

/// What selection needs to know of an adapter.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AdapterFacts {
    pub name: String,
    /// PCI vendor id (0x10de NVIDIA, 0x1002 AMD).
    pub vendor: u32,
    /// `domain:bus:device.function`, as wgpu reports it; empty when the driver does not.
    pub pci_bus_id: String,
    /// Vulkan's `deviceUUID`, when the driver gives one.
    pub uuid: Option<[u8; 16]>,
}

/// The variables a scheduler sets, with the vendor whose GPUs they count.
/// HIP's is read before ROCR's: with both set, HIP's index counts among ROCR's devices.
pub const ASSIGNMENT_VARIABLES: [(&str, u32, &str); 3] = [
    ("CUDA_VISIBLE_DEVICES", 0x10de, "NVIDIA"),
    ("HIP_VISIBLE_DEVICES", 0x1002, "AMD"),
    ("ROCR_VISIBLE_DEVICES", 0x1002, "AMD"),
];

/// The adapter chosen, and a line for the user saying why (none for the default).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Selected {
    pub index: usize,
    pub reason: Option<String>,
}

/// `--adapter`: an index into `adapters` (as `wgtrace info` numbers them), or text found
/// in an adapter's name, case-insensitively (the first such adapter).
pub fn by_argument(arg: &str, adapters: &[AdapterFacts]) -> Result<Selected, String> {
    let arg = arg.trim();
    let list = || {
        adapters
            .iter()
            .enumerate()
            .map(|(i, a)| format!("[{i}] {}", a.name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Ok(index) = arg.parse::<usize>() {
        if index >= adapters.len() {
            return Err(format!(
                "--adapter {index}: there are {} Vulkan adapters ({})",
                adapters.len(),
                list()
            ));
        }
        return Ok(Selected {
            index,
            reason: None,
        });
    }
    let wanted = arg.to_lowercase();
    adapters
        .iter()
        .position(|a| a.name.to_lowercase().contains(&wanted))
        .map(|index| Selected {
            index,
            reason: Some(format!("--adapter {arg}")),
        })
        .ok_or_else(|| format!("--adapter {arg:?} names no Vulkan adapter ({})", list()))
}

/// The adapter a scheduler assigned through the first of [`ASSIGNMENT_VARIABLES`] that
/// `var` finds set to a device list; `Ok(None)` when none is, or when it lists no device
/// (empty, `NoDevFiles`, `-1`). A variable naming a device no adapter is refuses, with
/// the reason; a variable set where Vulkan sees none of that vendor's GPUs (its Vulkan
/// driver is not installed) gives the default adapter with a note saying so.
pub fn assigned(
    var: &dyn Fn(&str) -> Option<String>,
    adapters: &[AdapterFacts],
) -> Result<Option<Selected>, String> {
    let listed = |v: &Option<String>| {
        v.as_deref()
            .and_then(|v| v.split(',').map(str::trim).next())
            .filter(|f| !f.is_empty() && *f != "NoDevFiles" && !f.starts_with('-'))
            .map(str::to_string)
    };
    for (name, vendor, vendor_name) in ASSIGNMENT_VARIABLES {
        let value = var(name);
        let Some(mut first) = listed(&value) else {
            continue;
        };
        let value = value.unwrap_or_default();
        // HIP_VISIBLE_DEVICES counts among the devices ROCR_VISIBLE_DEVICES leaves visible
        if name == "HIP_VISIBLE_DEVICES" {
            if let (Ok(k), Some(rocr)) = (first.parse::<usize>(), var("ROCR_VISIBLE_DEVICES")) {
                if let Some(d) = rocr.split(',').map(str::trim).nth(k) {
                    first = d.to_string();
                }
            }
        }
        let first = first.as_str();
        if first.starts_with("MIG-") {
            // Vulkan cannot render on a MIG instance
            return Ok(Some(Selected {
                index: 0,
                reason: Some(format!(
                    "{name}={value} assigns a MIG instance, which Vulkan cannot render on; \
                     rendering on the preferred adapter"
                )),
            }));
        }
        // the vendor's adapters in PCI bus order (enumeration order where a driver
        // reports no bus)
        let mut own: Vec<usize> = (0..adapters.len())
            .filter(|&i| adapters[i].vendor == vendor)
            .collect();
        own.sort_by(|&a, &b| adapters[a].pci_bus_id.cmp(&adapters[b].pci_bus_id));
        if own.is_empty() {
            return Ok(Some(Selected {
                index: 0,
                reason: Some(format!(
                    "{name}={value} assigns an {vendor_name} GPU, but Vulkan sees none (is \
                     its Vulkan driver installed?); rendering on the preferred adapter"
                )),
            }));
        }
        let pick = if let Ok(k) = first.parse::<usize>() {
            own.get(k).copied().ok_or_else(|| {
                format!(
                    "{name}={value} names {vendor_name} GPU {k}, but Vulkan sees {} {vendor_name} \
                     GPUs; pass --adapter to choose one",
                    own.len()
                )
            })?
        } else {
            let uuid = parse_uuid(first).ok_or_else(|| {
                format!("{name}={value}: {first:?} is neither a GPU index nor a GPU UUID")
            })?;
            own.iter()
                .copied()
                .find(|&i| adapters[i].uuid == Some(uuid))
                .ok_or_else(|| {
                    format!(
                        "{name}={value}: no Vulkan adapter has the UUID {first} (the {} \
                         {vendor_name} GPUs: {}); pass --adapter to choose one",
                        own.len(),
                        own.iter()
                            .map(|&i| adapters[i].uuid.map_or("none".into(), format_uuid))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                })?
        };
        let bus = &adapters[pick].pci_bus_id;
        return Ok(Some(Selected {
            index: pick,
            reason: Some(format!(
                "{name}={value}{}",
                if bus.is_empty() {
                    String::new()
                } else {
                    format!(": PCI bus {bus}")
                }
            )),
        }));
    }
    Ok(None)
}

/// Whether a scheduler's variable names a device by UUID (which must then be read from
/// every adapter).
pub fn wants_uuids(var: &dyn Fn(&str) -> Option<String>) -> bool {
    ASSIGNMENT_VARIABLES.iter().any(|(name, ..)| {
        var(name).is_some_and(|v| v.split(',').any(|d| parse_uuid(d.trim()).is_some()))
    })
}

/// A GPU UUID as CUDA and ROCm write it: `GPU-` then 32 hex digits, with or without
/// dashes between them.
pub fn parse_uuid(s: &str) -> Option<[u8; 16]> {
    let hex: String = s
        .strip_prefix("GPU-")
        .unwrap_or(s)
        .chars()
        .filter(|&c| c != '-')
        .collect();
    if hex.len() != 32 || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
        return None;
    }
    let mut out = [0u8; 16];
    for (i, byte) in out.iter_mut().enumerate() {
        *byte = u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).ok()?;
    }
    Some(out)
}

/// A UUID as nvidia-smi writes it: `GPU-8-4-4-4-12` hex digits.
pub fn format_uuid(u: [u8; 16]) -> String {
    let h: String = u.iter().map(|b| format!("{b:02x}")).collect();
    format!(
        "GPU-{}-{}-{}-{}-{}",
        &h[0..8],
        &h[8..12],
        &h[12..16],
        &h[16..20],
        &h[20..32]
    )
}

/// The adapter a render uses: `--adapter` when given, else a scheduler's assignment,
/// else index 0.
pub fn select(
    arg: Option<&str>,
    var: &dyn Fn(&str) -> Option<String>,
    adapters: &[AdapterFacts],
) -> Result<Selected, String> {
    match arg {
        Some(a) => by_argument(a, adapters),
        None => Ok(assigned(var, adapters)?.unwrap_or(Selected {
            index: 0,
            reason: None,
        })),
    }
}
