//! ROS 2 names checked before the node joins the graph: node names, namespaces and topic names, by the
//! rules of ROS 2's design article "Topic and Service name mapping to DDS" (as `rcl` checks them).

use crate::error::{Result, Ros2Error};

/// Longest node name or namespace ROS 2 accepts (`rmw`'s limit on the DDS name they become).
const MAX_NAME_LEN: usize = 255;

/// Checks a node name: letters, digits and underscores, not starting with a digit.
pub fn check_node_name(name: &str) -> Result<()> {
    let bad = |why: String| Ros2Error::Name {
        what: "node name",
        name: name.to_owned(),
        why,
    };
    if name.is_empty() {
        return Err(bad("it is empty".to_owned()));
    }
    if name.len() > MAX_NAME_LEN {
        return Err(bad(format!("longer than {MAX_NAME_LEN} characters")));
    }
    token_rule(name).map_err(bad)
}

/// Checks a namespace: absolute (`/` or `/a/b`), tokens of letters, digits and underscores, none
/// starting with a digit, no empty token (`//`) and no trailing `/`.
pub fn check_namespace(namespace: &str) -> Result<()> {
    let bad = |why: String| Ros2Error::Name {
        what: "namespace",
        name: namespace.to_owned(),
        why,
    };
    let Some(rest) = namespace.strip_prefix('/') else {
        return Err(bad("a namespace starts with `/` (e.g. /robot)".to_owned()));
    };
    if namespace.len() > MAX_NAME_LEN {
        return Err(bad(format!("longer than {MAX_NAME_LEN} characters")));
    }
    if rest.is_empty() {
        return Ok(());
    }
    rest.split('/').try_for_each(token_rule).map_err(bad)
}

/// Checks a topic name: absolute (`/foot/pressure`) or relative to the node's namespace
/// (`foot/pressure`); tokens as in a namespace, and no `__` (reserved by ROS 2).
pub fn check_topic_name(topic: &str) -> Result<()> {
    let bad = |why: String| Ros2Error::Name {
        what: "topic name",
        name: topic.to_owned(),
        why,
    };
    let relative = topic.strip_prefix('/').unwrap_or(topic);
    if relative.is_empty() {
        return Err(bad("it has no name after the `/`".to_owned()));
    }
    if relative.starts_with('~') || relative.contains('{') {
        return Err(bad(
            "`~` and `{}` substitutions are not supported: give the full name".to_owned(),
        ));
    }
    if topic.contains("__") {
        return Err(bad("`__` is reserved in ROS 2 names".to_owned()));
    }
    relative.split('/').try_for_each(token_rule).map_err(bad)
}

/// The absolute name of `topic` in `namespace` (both checked): relative names are in the namespace.
pub fn resolve_topic(namespace: &str, topic: &str) -> String {
    if topic.starts_with('/') {
        topic.to_owned()
    } else {
        format!("{}/{topic}", namespace.trim_end_matches('/'))
    }
}

/// One token of a name: non-empty, letters, digits and underscores, not starting with a digit.
fn token_rule(token: &str) -> Result<(), String> {
    let Some(first) = token.chars().next() else {
        return Err("an empty part (`//` or a trailing `/`)".to_owned());
    };
    if first.is_ascii_digit() {
        return Err(format!("the part {token:?} starts with a digit"));
    }
    match token
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '_'))
    {
        Some(c) => Err(format!(
            "{c:?} is not allowed (letters, digits and `_` only, parts separated by `/`)"
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_names_follow_the_ros2_rules() {
        assert!(check_node_name("presrs").is_ok());
        assert!(check_node_name("foot_2").is_ok());
        for bad in ["", "2foot", "foot-left", "foot/left", "ä", &"a".repeat(256)] {
            assert!(check_node_name(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn namespaces_are_absolute_without_empty_parts() {
        for good in ["/", "/robot", "/robot/left_foot"] {
            assert!(check_namespace(good).is_ok(), "{good}");
        }
        for bad in [
            "",
            "robot",
            "/robot/",
            "//robot",
            "/robot//foot",
            "/1robot",
            "/ro bot",
        ] {
            let err = check_namespace(bad).unwrap_err().to_string();
            assert!(err.contains("namespace"), "{bad}: {err}");
        }
    }

    #[test]
    fn relative_topics_are_resolved_in_the_namespace() {
        assert_eq!(resolve_topic("/", "foot/pressure"), "/foot/pressure");
        assert_eq!(resolve_topic("/robot", "presrs/gait"), "/robot/presrs/gait");
        assert_eq!(resolve_topic("/robot", "/diagnostics"), "/diagnostics");
    }

    #[test]
    fn topic_names_may_be_relative_but_not_substituted() {
        for good in ["/foot/pressure", "foot/pressure", "pressure", "/a1/b_2"] {
            assert!(check_topic_name(good).is_ok(), "{good}");
        }
        for bad in [
            "", "/", "/foot/", "//foot", "foot//p", "~/p", "{ns}/p", "/9p", "/a__b", "/a-b",
        ] {
            assert!(check_topic_name(bad).is_err(), "{bad}");
        }
    }
}
