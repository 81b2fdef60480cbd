//! ROS 2 names checked before the node joins the graph: node names, namespaces and topic names, by the
//! rules of ROS 2's design article "Topic and Service name mapping to DDS" (as `rcl` checks them).
//!
//! The rules for the characters and the slashes are ros2-client's ([`NodeName`], [`Name`]). This
//! module adds what ros2-client leaves out: the parts of a namespace (its `NodeName` lets `//robot`
//! and `/1robot` through, which ROS 2 refuses), the length limit, a refusal of `~` and `{}`
//! substitutions that says so, errors that name the bad name and why, and resolving a relative topic
//! in the namespace.

use ros2_client::names::NameError;
use ros2_client::{Name, NodeName};

use crate::error::{Result, Ros2Error};

/// Longest node name or namespace ROS 2 accepts (`rmw`'s limit on the DDS name they become).
const MAX_NAME_LEN: usize = 255;

/// Checks a node name: letters, digits and underscores, not starting with a digit.
pub fn check_node_name(name: &str) -> Result<()> {
    let bad = invalid("node name", name);
    if name.is_empty() {
        return Err(bad("it is empty".to_owned()));
    }
    if name.len() > MAX_NAME_LEN {
        return Err(bad(format!("longer than {MAX_NAME_LEN} characters")));
    }
    check_part(name).map_err(|e| bad(why(&e)))
}

/// Checks a namespace: absolute (`/` or `/a/b`), parts as node names, no empty part (`//`) and no
/// trailing `/`.
pub fn check_namespace(namespace: &str) -> Result<()> {
    let bad = invalid("namespace", namespace);
    let Some(rest) = namespace.strip_prefix('/') else {
        return Err(bad("a namespace starts with `/` (e.g. /robot)".to_owned()));
    };
    if namespace.len() > MAX_NAME_LEN {
        return Err(bad(format!("longer than {MAX_NAME_LEN} characters")));
    }
    if rest.is_empty() {
        return Ok(());
    }
    rest.split('/')
        .try_for_each(check_part)
        .map_err(|e| bad(why(&e)))
}

/// Checks a topic name: absolute (`/foot/pressure`) or relative to the node's namespace
/// (`foot/pressure`); parts as in a namespace, and no `__` (reserved by ROS 2).
pub fn check_topic_name(topic: &str) -> Result<()> {
    let bad = invalid("topic name", topic);
    let relative = topic.strip_prefix('/').unwrap_or(topic);
    if relative.is_empty() {
        return Err(bad("it has no name after the `/`".to_owned()));
    }
    // ros2-client refuses them too, but as a bad character.
    if relative.starts_with('~') || relative.contains('{') {
        return Err(bad(
            "`~` and `{}` substitutions are not supported: give the full name".to_owned(),
        ));
    }
    Name::parse(topic).map(drop).map_err(|e| bad(why(&e)))
}

/// The absolute name of `topic` in `namespace` (both checked): relative names are in the namespace.
pub fn resolve_topic(namespace: &str, topic: &str) -> String {
    if topic.starts_with('/') {
        topic.to_owned()
    } else {
        format!("{}/{topic}", namespace.trim_end_matches('/'))
    }
}

/// One part of a node name or a namespace, by ros2-client's rule for a node's base name (ROS 2's
/// rule for a part): non-empty, letters, digits and underscores, not starting with a digit.
fn check_part(part: &str) -> Result<(), NameError> {
    NodeName::new("/", part).map(drop)
}

/// The error of a bad `what` called `name`, given why.
fn invalid<'a>(what: &'static str, name: &'a str) -> impl Fn(String) -> Ros2Error + 'a {
    move |why| Ros2Error::Name {
        what,
        name: name.to_owned(),
        why,
    }
}

/// Why ros2-client refused a name, in ROS 2's terms (a whole empty name is caught before).
fn why(error: &NameError) -> String {
    match error {
        NameError::Empty | NameError::BadSlash(..) => {
            "an empty part (`//` or a trailing `/`)".to_owned()
        }
        // `_` is allowed anywhere: ros2-client names it only for a `__`.
        NameError::BadChar('_') => "`__` is reserved in ROS 2 names".to_owned(),
        NameError::BadChar(c) if c.is_ascii_digit() => {
            format!("a digit ({c:?}) cannot start a name or a part of one")
        }
        // ros2-client's `?` for a bad part before the last `/` (or a `?` itself).
        NameError::BadChar('?') => "a part has a character other than letters, digits and `_`, \
                                    starts with a digit or has `__`"
            .to_owned(),
        NameError::BadChar(c) => {
            format!("{c:?} is not allowed (letters, digits and `_` only, parts separated by `/`)")
        }
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

    #[test]
    fn errors_name_the_name_and_say_why() {
        let why = |result: Result<()>| result.unwrap_err().to_string();
        let namespace = why(check_namespace("/robot//foot"));
        assert!(namespace.contains("\"/robot//foot\"") && namespace.contains("empty part"));
        assert!(why(check_namespace("/1robot")).contains("digit"));
        assert!(why(check_node_name("foot-left")).contains("'-' is not allowed"));
        assert!(why(check_topic_name("/a__b")).contains("`__` is reserved"));
        assert!(why(check_topic_name("~/p")).contains("substitutions"));
        assert!(why(check_topic_name("/9p")).contains("digit"));
    }
}
