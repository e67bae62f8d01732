//! The values of an option that is one of a library's [`Choice`]s, listed and parsed by clap as
//! a `ValueEnum` would (`[possible values: ...]`, the same refusal of any other value).

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use mtec_workflow::Choice;
use std::ffi::OsStr;
use std::marker::PhantomData;

/// The value parser of a `T` option: `#[arg(long, value_parser = choice::<T>())]`.
pub fn choice<T: Choice>() -> Choices<T> {
    Choices(PhantomData)
}

#[derive(Clone)]
pub struct Choices<T>(PhantomData<T>);

fn possible<T: Choice>(c: T) -> PossibleValue {
    possible_value(c.name(), c.help())
}

/// The value `name` with its one line of `help` ("" for none).
pub fn possible_value(name: &'static str, help: &'static str) -> PossibleValue {
    match help {
        "" => PossibleValue::new(name),
        help => PossibleValue::new(name).help(help),
    }
}

impl<T: Choice> TypedValueParser for Choices<T> {
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<T, clap::Error> {
        // a value that is not UTF-8 is an invalid value (as for a `ValueEnum`), shown lossily
        let value = value.to_string_lossy();
        let parser = PossibleValuesParser::new(T::ALL.iter().map(|c| possible(*c)));
        let name = parser.parse_ref(cmd, arg, OsStr::new(value.as_ref()))?;
        let ignore_case = arg.is_some_and(|a| a.is_ignore_case_set());
        let found = T::ALL
            .iter()
            .find(|c| possible(**c).matches(&name, ignore_case));
        Ok(*found.expect("the parser accepts only the listed values"))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(T::ALL.iter().map(|c| possible(*c))))
    }
}
