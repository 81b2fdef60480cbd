//! Option values checked from their text, as the faces take them: counts, numbers, seconds, fractions,
//! addresses, `NAME=VALUE` pairs, terrain images and tracks. Each returns what was wrong as a sentence
//! (the command line's parser shows it as clap's error, exit code 2).

use std::net::SocketAddr;
use std::path::PathBuf;

use presrs_sim::dataset::BUILTIN_TERRAINS;

/// A whole number of at least 1.
pub fn positive_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!(
            "expected a whole number of at least 1, got {text:?}"
        )),
    }
}

/// A finite number above 0.
pub fn positive_number(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("expected a finite number above 0, got {text:?}")),
    }
}

/// A time limit in seconds: finite, above 0 and at most a billion (about 31 years; `Duration` cannot
/// hold every f64).
pub fn positive_seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 && x <= 1e9 => Ok(x),
        _ => Err(format!(
            "expected a number of seconds above 0 and at most 1e9, got {text:?}"
        )),
    }
}

/// A wait in seconds: finite, 0 or more and at most a billion.
pub fn non_negative_seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && (0.0..=1e9).contains(&x) => Ok(x),
        _ => Err(format!(
            "expected a number of seconds from 0 to 1e9, got {text:?}"
        )),
    }
}

/// `IP:PORT`, e.g. 127.0.0.1:7700.
pub fn socket_addr(text: &str) -> Result<SocketAddr, String> {
    text.trim()
        .parse()
        .map_err(|_| format!("expected IP:PORT (e.g. 127.0.0.1:7700), got {text:?}"))
}

/// A loopback `IP:PORT` (what `stream --listen` serves on).
pub fn loopback_addr(text: &str) -> Result<SocketAddr, String> {
    let addr = socket_addr(text)?;
    if addr.ip().is_loopback() {
        Ok(addr)
    } else {
        Err(format!(
            "{text}: only loopback addresses are served (127.0.0.1 or [::1])"
        ))
    }
}

/// `NAME=VALUE` with neither side empty (both trimmed); `what` names the form in the message.
pub fn name_value(text: &str, what: &str) -> Result<(String, String), String> {
    text.split_once('=')
        .map(|(n, v)| (n.trim(), v.trim()))
        .filter(|(n, v)| !n.is_empty() && !v.is_empty())
        .map(|(n, v)| (n.to_owned(), v.to_owned()))
        .ok_or_else(|| format!("expected {what}, got {text:?}"))
}

/// A fraction in (0, 1] (`--stance-threshold`, `--stance-hysteresis`).
pub fn fraction(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(value) if value > 0.0 && value <= 1.0 => Ok(value),
        _ => Err(format!("expected a fraction in (0, 1], got {text:?}")),
    }
}

/// A positive, finite number of seconds (`--frame-period`).
pub fn period_seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(value) if value.is_finite() && value > 0.0 => Ok(value),
        _ => Err(format!(
            "expected a positive number of seconds, got {text:?}"
        )),
    }
}

/// `--extra-load`: a finite fraction above -1 (the heavier hopper's mass stays positive).
pub fn extra_load(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > -1.0 => Ok(x),
        _ => Err(format!(
            "expected a fraction of the nominal body mass above -1 (the test hopper weighs nominal x \
             (1 + EXTRA_LOAD)), got {text:?}"
        )),
    }
}

/// `--terrain-image NAME=PNG`, checked for its form and name (the image is read later).
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainImage {
    pub name: String,
    pub path: PathBuf,
}

/// Parses `NAME=PNG`; NAME must not be a built-in terrain's (the built-in would be simulated, never the
/// image).
pub fn terrain_image(text: &str) -> Result<TerrainImage, String> {
    let (name, path) = name_value(text, "NAME=PNG")?;
    if BUILTIN_TERRAINS.contains(&name.as_str()) {
        return Err(format!(
            "{name} is a built-in terrain ({}); give the image another name, e.g. {name}_image={path}",
            BUILTIN_TERRAINS.join(", ")
        ));
    }
    Ok(TerrainImage {
        name,
        path: PathBuf::from(path),
    })
}

/// Checks a track (`TERRAIN:METRES,...` of built-in terrains); returns it as given.
pub fn track(text: &str) -> Result<String, String> {
    let segments = presrs_sim::track::parse_track(text).map_err(|e| match e {
        presrs_sim::SimError::Param { reason, .. } => reason,
        other => other.to_string(),
    })?;
    if let Some(unknown) = segments
        .iter()
        .find(|s| !BUILTIN_TERRAINS.contains(&s.terrain.as_str()))
    {
        return Err(format!(
            "unknown terrain {:?}; a track runs on the built-in terrains {}",
            unknown.terrain,
            BUILTIN_TERRAINS.join(", ")
        ));
    }
    Ok(text.to_owned())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn values_are_judged_alone() {
        assert_eq!(positive_count("3").unwrap(), 3);
        for bad in ["0", "-1", "x", ""] {
            assert!(positive_count(bad).is_err(), "{bad}");
        }
        assert_eq!(positive_number("0.5").unwrap(), 0.5);
        assert_eq!(non_negative_seconds("0").unwrap(), 0.0);
        for bad in ["-1", "nan", "inf", "2e9", "x"] {
            assert!(non_negative_seconds(bad).is_err(), "{bad}");
        }
        for bad in ["0", "-5", "nan", "inf", "x"] {
            assert!(positive_number(bad).is_err(), "{bad}");
        }
        assert!(socket_addr("nonsense").is_err());
        assert!(loopback_addr("127.0.0.1:0").is_ok());
        assert!(loopback_addr("[::1]:7700").is_ok());
        let err = loopback_addr("0.0.0.0:0").unwrap_err();
        assert!(err.contains("only loopback"), "{err}");
        assert_eq!(
            name_value(" grass = G3 ", "TERRAIN=GAIT").unwrap(),
            ("grass".to_owned(), "G3".to_owned())
        );
        for bad in ["wood", "=G1", "wood=", "="] {
            assert!(name_value(bad, "TERRAIN=GAIT").is_err(), "{bad}");
        }
    }

    #[test]
    fn fractions_periods_loads_images_and_tracks_are_checked() {
        assert_eq!(fraction("1").unwrap(), 1.0);
        for bad in ["0", "1.5", "-0.1", "x"] {
            assert!(fraction(bad).is_err(), "{bad}");
        }
        assert_eq!(period_seconds(" 0.01 ").unwrap(), 0.01);
        assert!(period_seconds("inf").is_err() && period_seconds("0").is_err());
        assert_eq!(extra_load("-0.5").unwrap(), -0.5);
        assert!(extra_load("-1").is_err() && extra_load("nan").is_err());
        let image = terrain_image("photo=grass.png").unwrap();
        assert_eq!(
            (image.name.as_str(), image.path),
            ("photo", PathBuf::from("grass.png"))
        );
        let err = terrain_image("grass=grass.png").unwrap_err();
        assert!(err.contains("built-in terrain"), "{err}");
        assert_eq!(track("wood:3,grass:3").unwrap(), "wood:3,grass:3");
        let err = track("wood:3,moon:2").unwrap_err();
        assert!(err.contains("unknown terrain \"moon\""), "{err}");
    }
}
