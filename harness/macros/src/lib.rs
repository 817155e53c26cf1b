//! `#[scenario]`: declares a conformance scenario where it is written.
//!
//! ```ignore
//! use ppmc::scenario::prelude::*;
//!
//! /// N - 1 = 0 moves exactly one step
//! #[scenario(tags("operation", "accel", "boundary"))]
//! fn s3_3_4_accel_one_step(d: &mut Driver) -> Outcome {
//!     /* ... */
//! }
//! ```
//!
//! The function becomes a constructor of its [`Scenario`]: the scenario's
//! name is the function's name, its one-line summary the doc comment, and
//! the body runs on a `Driver`. The datasheet section is written once:
//! taken from a name that starts with it (`s3_3_4_...` proves 3-3-4), or
//! given as `section = "3-1-1"` when the name does not carry one. A name
//! that carries a section may name another one in the same clause with
//! `section` (a 3-3-7 command proving a rule stated in 3-3-4); naming the
//! same section twice, or one from another clause, is a compile error.
//!
//! Arguments: `tags("a", "b")` (required), `section = "3-2-1"`,
//! `budget = <Duration expression>` (virtual time the scenario may use).
//!
//! [`Scenario`]: https://docs.rs/ppmc (ppmc::scenario::Scenario)

use proc_macro::TokenStream;
use proc_macro2::Span;
use quote::quote;
use syn::parse::Parser;
use syn::punctuated::Punctuated;
use syn::{Expr, ItemFn, LitStr, Meta, Token};

#[proc_macro_attribute]
pub fn scenario(args: TokenStream, item: TokenStream) -> TokenStream {
    match expand(args.into(), item.into()) {
        Ok(t) => t.into(),
        Err(e) => e.to_compile_error().into(),
    }
}

fn expand(
    args: proc_macro2::TokenStream,
    item: proc_macro2::TokenStream,
) -> syn::Result<proc_macro2::TokenStream> {
    let mut section: Option<LitStr> = None;
    let mut tags: Option<Vec<LitStr>> = None;
    let mut budget: Option<Expr> = None;
    let parser = syn::meta::parser(|meta| {
        if meta.path.is_ident("section") {
            section = Some(meta.value()?.parse()?);
        } else if meta.path.is_ident("budget") {
            budget = Some(meta.value()?.parse()?);
        } else if meta.path.is_ident("tags") {
            let content;
            syn::parenthesized!(content in meta.input);
            let list = Punctuated::<LitStr, Token![,]>::parse_terminated(&content)?;
            tags = Some(list.into_iter().collect());
        } else {
            return Err(meta.error("expected `tags(...)`, `section = \"...\"` or `budget = ...`"));
        }
        Ok(())
    });
    parser.parse2(args)?;

    let func: ItemFn = syn::parse2(item)?;
    let ident = &func.sig.ident;
    let name = ident.to_string();
    let tags = tags.ok_or_else(|| {
        syn::Error::new_spanned(ident, "a scenario needs `tags(\"...\")` (at least one)")
    })?;
    if tags.is_empty() {
        return Err(syn::Error::new_spanned(
            ident,
            "a scenario needs at least one tag",
        ));
    }
    let section = resolve_section(&name, section.as_ref(), ident.span())?;
    let summary = summary(&func)?;

    let vis = &func.vis;
    let inputs = &func.sig.inputs;
    let output = &func.sig.output;
    let block = &func.block;
    let docs = func.attrs.iter().filter(|a| a.path().is_ident("doc"));
    let other_attrs = func.attrs.iter().filter(|a| !a.path().is_ident("doc"));
    let budget = budget.map(|b| quote!(.budget(#b)));
    Ok(quote! {
        #(#docs)*
        #[doc = ""]
        #[doc = concat!("Scenario `", #name, "`, Section ", #section, ".")]
        #vis fn #ident() -> ::ppmc::scenario::Scenario {
            #(#other_attrs)*
            fn body(#inputs) #output #block
            ::ppmc::scenario::Scenario::new(#name, #section, #summary, &[#(#tags),*], body) #budget
        }
    })
}

/// The section a scenario proves: from its name, or given once.
fn resolve_section(name: &str, given: Option<&LitStr>, span: Span) -> syn::Result<String> {
    let in_name = section_in_name(name);
    match (given, in_name) {
        (None, Some(s)) => Ok(s.join("-")),
        (None, None) => Err(syn::Error::new(
            span,
            format!(
                "scenario `{name}`: its name does not start with a section (s3_3_4_...), \
                 so give one: #[scenario(section = \"3-1-1\", ...)]"
            ),
        )),
        (Some(lit), in_name) => {
            let s = lit.value();
            let parts: Vec<&str> = s.split('-').collect();
            if parts.len() < 2
                || parts
                    .iter()
                    .any(|p| p.is_empty() || !p.bytes().all(|b| b.is_ascii_digit()))
            {
                return Err(syn::Error::new_spanned(
                    lit,
                    "a section is written like 3-3-4 (numbers joined by -)",
                ));
            }
            if let Some(n) = in_name {
                if n == parts {
                    return Err(syn::Error::new_spanned(
                        lit,
                        format!("the section {s} is already in the name `{name}`; drop `section`"),
                    ));
                }
                if n[..2] != parts[..2] {
                    return Err(syn::Error::new_spanned(
                        lit,
                        format!(
                            "the name `{name}` says Section {}, but `section` says {s}: \
                             outside clause {}-{}",
                            n.join("-"),
                            n[0],
                            n[1]
                        ),
                    ));
                }
            }
            Ok(s)
        }
    }
}

/// `s3_3_4_accel` → `["3", "3", "4"]`; `None` unless at least two numbers.
fn section_in_name(name: &str) -> Option<Vec<&str>> {
    let rest = name.strip_prefix('s')?;
    let parts: Vec<&str> = rest
        .split('_')
        .take_while(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()))
        .collect();
    (parts.len() >= 2).then_some(parts)
}

/// The doc comment, one line.
fn summary(func: &ItemFn) -> syn::Result<String> {
    let mut lines = Vec::new();
    for a in &func.attrs {
        if let Meta::NameValue(nv) = &a.meta {
            if nv.path.is_ident("doc") {
                if let Expr::Lit(syn::ExprLit {
                    lit: syn::Lit::Str(s),
                    ..
                }) = &nv.value
                {
                    lines.push(s.value().trim().to_string());
                }
            }
        }
    }
    let text = lines
        .iter()
        .filter(|l| !l.is_empty())
        .cloned()
        .collect::<Vec<_>>()
        .join(" ");
    if text.is_empty() {
        return Err(syn::Error::new_spanned(
            &func.sig.ident,
            "a scenario needs a doc comment: its one-line summary",
        ));
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error_of(args: proc_macro2::TokenStream, item: proc_macro2::TokenStream) -> String {
        expand(args, item).expect_err("refused").to_string()
    }

    #[test]
    fn a_scenario_becomes_a_constructor_named_after_it_with_its_doc_as_summary() {
        let out = expand(
            quote!(tags("operation", "accel")),
            quote! {
                /// one step
                /// and no more
                fn s3_3_4_accel_one(d: &mut Driver) -> Outcome { Ok(()) }
            },
        )
        .expect("expands")
        .to_string();
        assert!(out.contains("fn s3_3_4_accel_one ()"), "{out}");
        assert!(
            out.contains(
                r#"Scenario :: new ("s3_3_4_accel_one" , "3-3-4" , "one step and no more""#
            ),
            "{out}"
        );
        assert!(out.contains(r#"& ["operation" , "accel"]"#), "{out}");
    }

    #[test]
    fn what_a_scenario_lacks_is_a_compile_error_that_says_so() {
        let body = quote!(
            fn s3_1_1_x(d: &mut Driver) -> Outcome {
                Ok(())
            }
        );
        assert!(error_of(quote!(tags("a")), body.clone()).contains("needs a doc comment"));
        let documented = quote! {
            /// x
            fn s3_1_1_x(d: &mut Driver) -> Outcome { Ok(()) }
        };
        assert!(error_of(quote!(), documented.clone()).contains("needs `tags"));
        assert!(error_of(quote!(tags()), documented.clone()).contains("at least one tag"));
        assert!(
            error_of(quote!(tags("a"), section = "3-1-1"), documented.clone())
                .contains("already in the name")
        );
        assert!(error_of(quote!(tags("a"), colour = "red"), documented).contains("expected"));
        let unnamed = quote! {
            /// x
            fn home_axis(d: &mut Driver) -> Outcome { Ok(()) }
        };
        assert!(error_of(quote!(tags("a")), unnamed).contains("give one"));
    }

    #[test]
    fn the_section_comes_from_the_name_or_is_given_once_in_the_same_clause() {
        let sp = Span::call_site();
        let lit = |s: &str| LitStr::new(s, sp);
        assert_eq!(
            resolve_section("s3_3_4_accel", None, sp).expect("resolves"),
            "3-3-4"
        );
        assert_eq!(
            resolve_section("s3_6_probe", None, sp).expect("resolves"),
            "3-6"
        );
        assert!(resolve_section("e0_undefined", None, sp).is_err());
        assert_eq!(
            resolve_section("e0_undefined", Some(&lit("3-1-1")), sp).expect("resolves"),
            "3-1-1"
        );
        assert_eq!(
            resolve_section("s3_3_7_pout", Some(&lit("3-3-4")), sp).expect("resolves"),
            "3-3-4"
        );
        assert!(resolve_section("s3_3_4_accel", Some(&lit("3-3-4")), sp).is_err());
        assert!(resolve_section("s3_5_1_x", Some(&lit("3-3-4")), sp).is_err());
        assert!(resolve_section("e1_x", Some(&lit("Table 3-3")), sp).is_err());
        assert!(section_in_name("s3_x").is_none());
    }
}
