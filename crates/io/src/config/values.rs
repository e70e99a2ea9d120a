//! Value shapes the sections share: a number or a 3-vector, a number or a pair, a
//! probability or `false`, one table or an array of tables.

use std::fmt;
use std::marker::PhantomData;

use serde::de::{self, MapAccess, SeqAccess, Visitor};
use serde::ser::SerializeSeq;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A number applied to all three axes, or an array of exactly three numbers.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Num3 {
    Scalar(f64),
    List(Vec<f64>),
}

impl Num3 {
    pub(super) fn from3(v: [f64; 3]) -> Self {
        if v[0] == v[1] && v[1] == v[2] {
            Num3::Scalar(v[0])
        } else {
            Num3::List(v.to_vec())
        }
    }
}

impl<'de> Deserialize<'de> for Num3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        deserialize_num_or_list(d, "a number or an array of 3 numbers")
    }
}

/// A number or an array of numbers; `expecting` names the shape in type errors.
fn deserialize_num_or_list<'de, D: Deserializer<'de>>(
    d: D,
    expecting: &'static str,
) -> Result<Num3, D::Error> {
    struct V(&'static str);
    impl<'de> Visitor<'de> for V {
        type Value = Num3;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str(self.0)
        }
        fn visit_f64<E: de::Error>(self, v: f64) -> Result<Num3, E> {
            Ok(Num3::Scalar(v))
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<Num3, E> {
            Ok(Num3::Scalar(v as f64))
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<Num3, E> {
            Ok(Num3::Scalar(v as f64))
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Num3, A::Error> {
            let mut v = Vec::new();
            while let Some(x) = seq.next_element::<f64>()? {
                v.push(x);
            }
            Ok(Num3::List(v))
        }
    }
    d.deserialize_any(V(expecting))
}

impl Serialize for Num3 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Num3::Scalar(x) => s.serialize_f64(*x),
            Num3::List(v) => v.serialize(s),
        }
    }
}

/// A number applied to both elements, or an array of exactly two numbers
/// (`nhc.std_mps`: lateral, vertical).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Num2(pub(super) Num3);

impl Num2 {
    pub(super) fn from2(v: [f64; 2]) -> Self {
        if v[0] == v[1] {
            Num2(Num3::Scalar(v[0]))
        } else {
            Num2(Num3::List(v.to_vec()))
        }
    }
}

impl<'de> Deserialize<'de> for Num2 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        deserialize_num_or_list(d, "a number or an array of 2 numbers").map(Num2)
    }
}

impl Serialize for Num2 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

/// An innovation-test probability, or `false` for no test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Gate {
    Probability(f64),
    Off,
}

impl<'de> Deserialize<'de> for Gate {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Gate;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a probability (e.g. 1e-4) or false (no innovation test)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Gate, E> {
                Ok(Gate::Probability(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Gate, E> {
                Ok(Gate::Probability(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Gate, E> {
                Ok(Gate::Probability(v as f64))
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Gate, E> {
                if v {
                    Err(E::custom(
                        "expected a probability (e.g. 1e-4) or false (no innovation test), got true",
                    ))
                } else {
                    Ok(Gate::Off)
                }
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for Gate {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Gate::Probability(p) => s.serialize_f64(*p),
            Gate::Off => s.serialize_bool(false),
        }
    }
}

impl Gate {
    pub(super) fn from_option(p: Option<f64>) -> Self {
        p.map_or(Gate::Off, Gate::Probability)
    }
}

/// One table or an array of tables.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct OneOrMany<T>(pub(super) Vec<T>);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for OneOrMany<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = OneOrMany<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a table or an array of tables")
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
                T::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(|t| OneOrMany(vec![t]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut v = Vec::new();
                while let Some(x) = seq.next_element::<T>()? {
                    v.push(x);
                }
                Ok(OneOrMany(v))
            }
        }
        d.deserialize_any(V(PhantomData))
    }
}

impl<T: Serialize> Serialize for OneOrMany<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.0.len() == 1 {
            self.0[0].serialize(s)
        } else {
            let mut seq = s.serialize_seq(Some(self.0.len()))?;
            for x in &self.0 {
                seq.serialize_element(x)?;
            }
            seq.end()
        }
    }
}

/// A string or an array of strings (`systems = "G,E"` or `["G", "E"]`); written
/// back as an array.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Strings(pub(super) Vec<String>);

impl<'de> Deserialize<'de> for Strings {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Strings;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a string or an array of strings")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
                Ok(Strings(vec![v.to_string()]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut v = Vec::new();
                while let Some(x) = seq.next_element::<String>()? {
                    v.push(x);
                }
                Ok(Strings(v))
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for Strings {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}
